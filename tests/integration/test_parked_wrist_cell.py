"""At home, the last wrist joint's turn changes nothing the top camera sees (what a look that kept it would rest on)."""

import numpy as np

from bt_arrange.motion import DEFAULT_HOME_Q
from bt_arrange_sim.pybullet.cell import WorkCell


def _turn_last_joint(cell: WorkCell, to_rad: float, periods: int = 150) -> None:
    """Ramp the last joint to ``to_rad`` at home, one setpoint per control period, and let it settle."""
    arm = cell.robot.arm
    start_rad = float(arm.joint_positions()[5])
    q = np.array(DEFAULT_HOME_Q, dtype=float)
    for k in range(1, periods + 1):
        q[5] = start_rad + (to_rad - start_rad) * k / periods
        arm.command(q)
        cell.step(1)
    cell.settle(0.2)


def test_the_top_cameras_image_is_the_same_at_any_turn_of_the_last_wrist_joint_at_home():
    with WorkCell() as cell:
        cell.add_cube("red", 0.45, 0.10, yaw_rad=0.3)
        cell.settle(0.3)
        home = cell.camera.capture().rgb
        for turn_rad in (2.5, -2.5, 5.5):
            _turn_last_joint(cell, DEFAULT_HOME_Q[5] + turn_rad)
            assert abs(cell.robot.arm.joint_positions()[5] - (DEFAULT_HOME_Q[5] + turn_rad)) < 0.01
            image = cell.camera.capture().rgb
            assert np.array_equal(image, home), f"the image changed with the last joint turned {turn_rad} rad"
