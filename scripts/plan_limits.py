"""Print what a plan file may ask for: the built-in colours, the usable area, part sizes and masses.

    python scripts/plan_limits.py

docs/plans.md shows this output (the figures are computed from the code: the simulated camera's
view, the arm's reach checks, the shape's and the gripper's limits), and ``scripts/figures.py``
reprints it beside the README's other deterministic figures.
"""

from __future__ import annotations

import colorsys

from bt_arrange.motion import ArmKinematics, gripper_down_pose
from bt_arrange.objects import CUBE, DEFAULT_PART_FRICTION
from bt_arrange.perception import DEFAULT_COLOUR_TABLE
from bt_arrange.settings import ManipulationSettings
from bt_arrange.shapes import ROBOTIQ_2F85
from bt_arrange.shapes.cuboid import MAX_HEIGHT_M, MIN_EDGE_M
from bt_arrange_sim.config import CameraConfig

STEP_MM = 25


def colours() -> None:
    """The built-in colours and their paint."""
    print("built-in colours (name: paint rgb; hue range deg; saturation; value)")
    for name in DEFAULT_COLOUR_TABLE.names:
        colour = DEFAULT_COLOUR_TABLE[name]
        paint = ", ".join(f"{v:.2f}" for v in colour.paint_rgb)
        hue = colorsys.rgb_to_hsv(*colour.paint_rgb)[0] * 360
        ranges = " and ".join(f"{low:g}..{high:g}" for low, high in colour.hue_ranges_deg)
        print(
            f"  {colour.name:<7} rgb = [{paint}] (hue {hue:.0f}); hue {ranges}; "
            f"saturation {colour.saturation_range[0]:g}..{colour.saturation_range[1]:g}; "
            f"value {colour.value_range[0]:g}..{colour.value_range[1]:g}"
        )


def usable_area() -> None:
    """The usable area of the table, as a picture."""
    settings = ManipulationSettings()
    kinematics = ArmKinematics()
    view = CameraConfig().view()
    grasp_m, approach_m, _ = settings.tcp_heights_m(CUBE.shape)

    def reachable(x_m: float, y_m: float) -> bool:
        for height_m in (grasp_m, approach_m):
            try:
                kinematics.check_reachable(gripper_down_pose(x_m, y_m, height_m, 0.0))
            except Exception:
                return False
        return True

    xs = list(range(1000, -1, -STEP_MM))
    ys = list(range(-600, 601, STEP_MM))
    both: list[tuple[int, int]] = []
    print(
        f"the usable area of a 50 mm cube at yaw 0, every {STEP_MM} mm (x up the page, y to the right; the arm's "
        "base at x 0, y 0):"
    )
    print("  # seen by the camera and in reach   c seen only   r in reach only   . neither   + the base")
    print("  x mm")
    for x in xs:
        row = []
        for y in ys:
            if x == 0 and y == 0:
                row.append("+")
                continue
            seen = view.sees_part(x / 1000, y / 1000, 0.0, CUBE)
            reach = reachable(x / 1000, y / 1000)
            row.append("#" if seen and reach else "c" if seen else "r" if reach else ".")
            if seen and reach:
                both.append((x, y))
        label = f"{x:5d}" if x % 100 == 0 else "     "
        print(f"  {label} {''.join(row)}")
    print(f"        y {ys[0]} mm {'-' * (len(ys) - 18)} y {ys[-1]} mm")
    x_values = sorted({x for x, _ in both})
    y_values = sorted({y for _, y in both})
    print(
        f"  usable (#): x {x_values[0]} to {x_values[-1]} mm, y {y_values[0]} to {y_values[-1]} mm "
        f"(the camera's view with {view.margin_m * 1000:.0f} mm around the top face; the reach at grasp and "
        "approach height); a part's whole top face must fit, so larger parts have less room"
    )


def parts() -> None:
    """The part sizes and masses a plan may ask for."""
    settings = ManipulationSettings()
    gripper = ROBOTIQ_2F85
    print("parts (cuboids):")
    print(
        f"  every edge at least {MIN_EDGE_M * 1000:.0f} mm, at most {MAX_HEIGHT_M * 1000:.0f} mm tall, and one "
        f"horizontal side at most {gripper.max_grasp_width_m * 1000:.0f} mm (the {gripper.stroke_m * 1000:.0f} mm "
        f"stroke less {gripper.grasp_clearance_m * 1000:.0f} mm): the smallest part is {MIN_EDGE_M * 1000:.0f} x "
        f"{MIN_EDGE_M * 1000:.0f} x {MIN_EDGE_M * 1000:.0f} mm, the largest {gripper.max_grasp_width_m * 1000:.0f} mm "
        f"across the pads and {MAX_HEIGHT_M * 1000:.0f} mm tall, its other side bounded by the usable area"
    )
    print(
        f"  mass at most {settings.max_payload_part_kg:.2f} kg for the arm (the UR5's {settings.arm_payload_kg:g} kg "
        f"payload less the gripper's {gripper.mass_kg:g} kg) and {settings.max_lift_kg(DEFAULT_PART_FRICTION):.2f} kg "
        f"for the pads (friction {gripper.pad_friction:g} x {DEFAULT_PART_FRICTION:g}, grip "
        f"{settings.grip_force_n:g} N, {settings.lift_safety:g} x to spare); friction 1.0 lifts "
        f"{settings.max_lift_kg(1.0):.2f} kg"
    )


def main() -> None:
    """Print everything."""
    colours()
    print()
    usable_area()
    print()
    parts()


if __name__ == "__main__":
    main()
