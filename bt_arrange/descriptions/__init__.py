"""Robot descriptions shipped with bt-arrange (URDF), loaded by placo and pybullet alike."""
