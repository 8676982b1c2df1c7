"""The pybullet engine: the work cell in pybullet, built on the engine-neutral layer of ``bt_arrange_sim``.

The rooms: ``objects`` (the parts as bodies), ``devices`` (the ``bt_arrange.robot`` interfaces),
``cell`` (``WorkCell``: the client, the robot, the parts, ground truth and error-injection access),
``runs`` (``SimWorld`` and ``SimulatedRun``), ``calibration`` (the ChArUco board on the flange),
``scripted`` (a pick and place without a tree) and ``backend`` (``SimBackend``, entry point ``sim``).
Only ``backend`` is imported by the command line; pybullet itself is imported when a cell is built.
"""
