"""The pybullet work cell of bt-arrange, installed as ``bt_arrange_sim``.

It implements the robot interfaces of ``bt_arrange.robot`` for a simulated UR5 with a
2F-85-like gripper, coloured 5 cm cubes and a top RGB-D camera.
"""

from bt_arrange_sim.cell import HOME_Q, CameraConfig, CellConfig, PhysicsConfig, WorkCell
from bt_arrange_sim.noise import CameraNoise, CameraNoiseConfig
from bt_arrange_sim.objects import PAINT_RGB, Contact

__all__ = [
    "HOME_Q",
    "PAINT_RGB",
    "CameraConfig",
    "CameraNoise",
    "CameraNoiseConfig",
    "CellConfig",
    "Contact",
    "PhysicsConfig",
    "WorkCell",
]
