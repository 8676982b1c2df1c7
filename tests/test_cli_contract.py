"""The CLI's contract for user mistakes: exit 2, exactly one line on stderr, no traceback, nothing simulated.

Every subcommand meets every kind of bad input. A spy stands in for the work cell and for the
experiment's trials: a mistake must be refused before either is reached. Generated argument lists
(hypothesis) either reach the spy (accepted, so they would run) or are refused by that contract.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import bt_arrange_sim.executors
import bt_arrange_sim.experiment
import bt_arrange_sim.pybullet.cell
import bt_arrange_sim.pybullet.runs
from bt_arrange import cli
from bt_arrange.calibration import CameraCalibration, rpy_matrix, write_calibration
from bt_arrange.geometry import Pose
from bt_arrange.robot import CameraIntrinsics

TREES = Path(__file__).resolve().parents[1] / "trees"
SINGLE = str(TREES / "single_cube.py")


class Simulated(BaseException):
    """Raised by the spies: the command got as far as building a world or running a trial.

    A ``BaseException``: a campaign records a trial's ``Exception`` as an errored trial and goes on.
    """


def spy(*_: object, **__: object) -> None:
    raise Simulated


@pytest.fixture(autouse=True)
def no_world(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(bt_arrange_sim.pybullet.runs, "WorkCell", spy)
    monkeypatch.setattr(bt_arrange_sim.pybullet.cell, "WorkCell", spy)
    monkeypatch.setattr(bt_arrange_sim.experiment.campaign, "run_trial", spy)
    monkeypatch.setattr(bt_arrange_sim.experiment.campaign, "ProcessPoolExecutor", spy)
    monkeypatch.setattr(bt_arrange_sim.executors, "open_executor", spy)
    # The scheduler's address is judged here, not whether one answers there (tests/test_dask_scheduler.py).
    monkeypatch.setattr(bt_arrange_sim.executors, "probe_scheduler", lambda scheduler: None)
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)


def call(argv: list[str]) -> tuple[int | str, str, str]:
    """Run the CLI in-process; the exit code, or "simulated" when a spy was reached."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code: int | str = cli.main(argv)
        except SystemExit as exit_:
            code = exit_.code if isinstance(exit_.code, int) else 2
        except Simulated:
            code = "simulated"
    return code, out.getvalue(), err.getvalue()


def assert_refused(code: int | str, err: str) -> str:
    assert code == 2, (code, err)
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("bt-arrange: error: "), err
    assert "Traceback" not in err
    return lines[0]


def tree(tmp_path: Path, name: str, body: str) -> str:
    path = tmp_path / name
    path.write_text(textwrap.dedent(body))
    return str(path)


GOOD_TREE = """
    from bt_arrange.trees import Target, arrangement
    from bt_arrange_sim.scenes import PartStart, scatter
    TARGETS = [Target("red", {x}, {y})]
    def create_root(threshold_mm=1.0):
        return arrangement(TARGETS, threshold_mm=threshold_mm)
    def create_scene(seed):
        return {scene}
"""


def bad_tree_files(tmp_path: Path) -> dict[str, tuple[str, str]]:
    """Tree files with one mistake each, and a fragment the error line must contain."""
    scene = 'scatter(["red"], seed, avoid=TARGETS)'
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    return {
        "missing": (str(tmp_path / "nope.py"), "nope.py not found"),
        "not python": (
            tree(tmp_path, "tree.txt", "x"),
            "is neither a Python file (.py), a BehaviorTree.CPP XML tree (.xml) nor a plan (.toml)",
        ),
        "syntax error": (tree(tmp_path, "syntax.py", "def create_root(:\n"), "syntax error at line 1"),
        "raises on import": (tree(tmp_path, "boom.py", "1 / 0\n"), "ZeroDivisionError"),
        "no create_root": (tree(tmp_path, "empty.py", "X = 1\n"), "defines no create_root()"),
        "create_root fails": (tree(tmp_path, "fails.py", "def create_root():\n    return {}['x']\n"), "KeyError"),
        "not a behaviour": (tree(tmp_path, "notbt.py", "def create_root():\n    return 3\n"), "returned int"),
        "unknown colour": (
            tree(
                tmp_path, "purple.py", GOOD_TREE.replace('"red", {x}', '"purple", {x}').format(x=0.5, y=0, scene=scene)
            ),
            "unknown colour 'purple'",
        ),
        "out of reach": (tree(tmp_path, "far.py", GOOD_TREE.format(x=1.2, y=0, scene=scene)), "out of reach"),
    }


def bad_run_files(tmp_path: Path) -> dict[str, tuple[str, str]]:
    """Tree files that only ``run`` refuses: their scene or their place in the cell is wrong."""
    scene = 'scatter(["red"], seed, avoid=TARGETS)'
    return {
        "no create_scene": (
            tree(tmp_path, "noscene.py", GOOD_TREE.format(x=0.5, y=0, scene=scene).replace("create_scene", "other")),
            "create_scene(seed)",
        ),
        "no cube for the target": (
            tree(tmp_path, "nocube.py", GOOD_TREE.format(x=0.5, y=0, scene='scatter(["blue"], seed)')),
            "no part 'red' in the scene",
        ),
        "target out of view": (
            tree(tmp_path, "view.py", GOOD_TREE.format(x=0.3, y=0.45, scene=scene)),
            "camera's view",
        ),
        "target behind the base": (tree(tmp_path, "behind.py", GOOD_TREE.format(x=-0.4, y=0, scene=scene)), "view"),
        "unknown cube colour": (
            tree(
                tmp_path, "paint.py", GOOD_TREE.format(x=0.5, y=0, scene=f'{scene} + [PartStart("pink", 0.4, 0.3, 0)]')
            ),
            "unknown colour 'pink'",
        ),
        "scene raises": (tree(tmp_path, "scene.py", GOOD_TREE.format(x=0.5, y=0, scene="1 / 0")), "create_scene()"),
    }


def test_every_bad_tree_file_is_one_line_for_run_and_show(tmp_path: Path) -> None:
    for command in ("run", "show"):
        for kind, (path, fragment) in bad_tree_files(tmp_path).items():
            code, _, err = call([command, path])
            assert fragment in assert_refused(code, err), (command, kind)


def test_every_tree_file_that_cannot_run_in_the_cell_is_one_line(tmp_path: Path) -> None:
    for kind, (path, fragment) in bad_run_files(tmp_path).items():
        code, _, err = call(["run", path])
        assert fragment in assert_refused(code, err), kind


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["run", SINGLE, "--seed", "-5"], "argument --seed: -5 must be 0 or more"),
        (["run", SINGLE, "--seed", "x"], "argument --seed: 'x' is not a whole number"),
        (["run", SINGLE, "--threshold-mm", "0"], "--threshold-mm"),
        (["run", SINGLE, "--threshold-mm", "nan"], "--threshold-mm"),
        (["run", SINGLE, "--threshold-mm", "abc"], "'abc' is not a number of millimetres"),
        (["run", SINGLE, "--threshold-mm", "0.05"], "below 0.07 mm, the smallest offset a push can correct"),
        (["run", SINGLE, "--time-limit-s", "0"], "argument --time-limit-s: 0 must be a positive number of seconds"),
        (["run", SINGLE, "--time-limit-s", "-1"], "--time-limit-s"),
        (["run", SINGLE, "--time-limit-s", "inf"], "--time-limit-s"),
        (["run", SINGLE, "--gui"], "needs a display"),
        (["run", SINGLE, "--record", "{file}"], "it is a file, not a folder"),
        (["run", SINGLE, "--record", "{file}/below"], "cannot record into"),
        (["run", SINGLE, "--bogus"], "unrecognized arguments: --bogus"),
        (["run"], "the following arguments are required: TREE_FILE"),
        (["show", SINGLE, "--format", "gif"], "argument --format: invalid choice: 'gif'"),
        (["show", SINGLE, "--out", "{file}/below.txt"], "below.txt"),
        (["experiment", "--seed", "-5"], "argument --seed: -5 must be 0 or more"),
        (["experiment", "--trials", "0"], "argument --trials: 0 must be 1 or more"),
        (["experiment", "--workers", "0"], "argument --workers: 0 must be 1 or more"),
        (["experiment", "--rows", "bogus"], "unknown row 'bogus'"),
        (["experiment", "--rows", ","], "--rows is empty"),
        (["experiment", "--threshold-mm", "-1", "--out", "{dir}"], "--threshold-mm"),
        (["experiment", "--threshold-mm", "0.05", "--out", "{dir}"], "below 0.07 mm"),
        (["experiment", "--out", "{file}"], "it is a file, not a folder"),
        (["experiment", "--thresholds", "0.05,1", "--out", "{dir}"], "--thresholds 0.05: threshold 0.05 mm is below"),
        (["experiment", "--thresholds", "1,x", "--out", "{dir}"], "--thresholds: 'x' is not a number"),
        (["experiment", "--thresholds", ",", "--out", "{dir}"], "--thresholds is empty"),
        (["experiment", "--threshold-mm", "1", "--thresholds", "1,2"], "give --threshold-mm or --thresholds, not both"),
        (["experiment", "--executor", "slurm"], "argument --executor: invalid choice: 'slurm'"),
        (["experiment", "--executor", "dask", "--workers", "0"], "argument --workers: 0 must be 1 or more"),
        (["experiment", "--scheduler", "tcp://10.0.0.5:8786", "--out", "{dir}"], "--scheduler needs --executor dask"),
        (["experiment", "--executor", "dask", "--scheduler", "", "--out", "{dir}"], "--scheduler is empty"),
        (["experiment", "--cell", "ideal,lab", "--out", "{dir}"], "--cell lab: unknown cell 'lab'"),
        (["experiment", "--object", "beam", "--out", "{dir}"], "--object 'beam': unknown object type 'beam'"),
        (["experiment", "--object", "bar", "--rows", "grasp-estimator", "--out", "{dir}"], "5 cm cube only"),
        (["experiment", "--object", "cube,beam", "--out", "{dir}"], "--object 'beam': unknown object type 'beam'"),
        (["experiment", "--object", " , ", "--out", "{dir}"], "--object ' , ' is empty"),
        (["experiment", "--object", "cube,bar", "--rows", "grasp-estimator", "--out", "{dir}"], "5 cm cube only"),
        (["info", "--bogus"], "unrecognized arguments: --bogus"),
        (["bogus"], "invalid choice: 'bogus'"),
        ([], "the following arguments are required: COMMAND"),
    ],
)
def test_every_subcommand_refuses_bad_options_in_one_line(tmp_path: Path, argv: list[str], fragment: str) -> None:
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    argv = [a.format(file=a_file, dir=tmp_path / "out") for a in argv]
    code, _, err = call(argv)
    assert fragment in assert_refused(code, err)


CELL_FILES = {
    "unknown_key.toml": ('preset = "real"\n[gripper]\nfinger_wobble = 1\n', "unknown key gripper.finger_wobble"),
    "unknown_table.toml": ("[lens]\nk1 = 0.1\n", "unknown key 'lens'"),
    "bad_value.toml": ("[camera]\nfocal_sigma_percent = -1\n", "camera.focal_sigma_percent = -1 must not be negative"),
    "bad_type.toml": ('[joints]\nenabled = "yes"\n', "joints.enabled = 'yes' must be true or false"),
    "bad_preset.toml": ('preset = "lab"\n', "preset 'lab' is not one of ideal, real"),
    "broken.toml": ("[camera\n", "is not valid TOML"),
}


@pytest.mark.parametrize("command", ["run", "experiment"])
@pytest.mark.parametrize(
    ("cell", "fragment"),
    [
        ("lab", "--cell lab: unknown cell 'lab': choose ideal or real, or give a .toml file"),
        (",", "--cell"),
        ("{dir}/missing.toml", "cannot read cell file"),
        *[(f"{{dir}}/{name}", fragment) for name, (_, fragment) in CELL_FILES.items()],
    ],
)
def test_a_bad_cell_is_refused_in_one_line_naming_the_key(
    tmp_path: Path, command: str, cell: str, fragment: str
) -> None:
    for name, (text, _) in CELL_FILES.items():
        (tmp_path / name).write_text(text)
    argv = ["run", SINGLE] if command == "run" else ["experiment", "--trials", "1", "--out", str(tmp_path / "out")]
    code, _, err = call([*argv, "--cell", cell.format(dir=tmp_path)])
    assert fragment in assert_refused(code, err)


def test_a_good_cell_reaches_the_world(tmp_path: Path) -> None:
    mine = tmp_path / "mine.toml"
    mine.write_text('preset = "real"\ncell_seed = 3\n[friction]\nenabled = false\n[gripper]\ncoupling_erp = 0.5\n')
    camera = write_calibration(
        CameraCalibration(
            intrinsics=CameraIntrinsics(1920, 1080, 1371.0, 1371.0, 959.5, 539.5),
            camera_to_base=Pose.from_rotation([0.5, 0.0, 0.7], rpy_matrix(math.pi, 0.0, math.radians(-93.0))),
            reprojection_error_px=0.1,
            views=20,
            cell="real",
            date="2026-12-01T10:00:00+00:00",
        ),
        tmp_path / "camera.toml",
    )
    for cell in ("real", "ideal", str(mine)):
        # A real cell runs on a calibrated camera only (refused without one: tests/test_cli_inject.py).
        calibration = ["--calibration", str(camera)] if cell == "real" else []
        assert call(["run", SINGLE, "--cell", cell, *calibration])[0] == "simulated"
        out = tmp_path / cell.replace("/", "_")
        assert call(["experiment", "--trials", "1", "--rows", "system", "--cell", cell, "--out", str(out)])[0] == (
            "simulated"
        )


def test_a_good_run_reaches_the_world_and_a_good_experiment_its_trials(tmp_path: Path) -> None:
    # The spies themselves work: what is accepted does get as far as simulating.
    assert call(["run", SINGLE])[0] == "simulated"
    assert call(["experiment", "--trials", "1", "--rows", "system", "--out", str(tmp_path / "x")])[0] == "simulated"
    campaigns = [
        ["--thresholds", "0.5,1", "--cell", "ideal,real", "--strategy", "learned"],
        ["--executor", "dask", "--workers", "2"],
        ["--executor", "dask", "--scheduler", "tcp://10.0.0.5:8786"],
        ["--workers", "2", "--rows", "all,tilt"],
    ]
    for i, options in enumerate(campaigns):
        argv = ["experiment", "--trials", "1", "--rows", "system", "--out", str(tmp_path / f"c{i}"), *options]
        assert call(argv)[0] == "simulated", options


@pytest.mark.parametrize(
    "argv",
    [
        ["run", SINGLE, "--seed", "-5"],
        ["run", SINGLE, "--inject", "nonsense"],
        ["experiment", "--trials", "0"],
        ["experiment", "--rows", "bogus"],
        ["show", SINGLE, "--format", "gif"],
    ],
)
def test_the_installed_command_prints_one_line_and_nothing_from_the_simulator(argv: list[str]) -> None:
    # A real process: C-level output (pybullet's banner) and the progress bar would show here.
    result = subprocess.run(
        [sys.executable, "-m", "bt_arrange.cli", *argv], capture_output=True, text=True, timeout=120, check=False
    )
    assert_refused(result.returncode, result.stderr)
    assert result.stdout == ""


# -- property-based: generated argument lists --------------------------------------------------

values = st.sampled_from(["0", "-1", "1", "2.5", "0.1", "nan", "inf", "-inf", "x", "", "1e400", "7", "0.3"])
run_options = st.lists(
    st.one_of(
        st.tuples(st.sampled_from(["--seed", "--threshold-mm", "--time-limit-s"]), values),
        st.tuples(st.sampled_from(["--json", "--live", "--gui", "--bogus"])),
        st.tuples(st.just("--inject"), st.sampled_from(["translation", "all,tilt", "nonsense", ",", ""])),
        st.tuples(st.just("--cell"), st.sampled_from(["ideal", "real"])),
    ),
    max_size=3,
)
experiment_options = st.lists(
    st.one_of(
        st.tuples(st.sampled_from(["--seed", "--threshold-mm", "--trials", "--workers"]), values),
        st.tuples(st.just("--rows"), st.sampled_from(["system", "bogus", ",", "system,translation", "", "all"])),
        st.tuples(st.just("--thresholds"), st.sampled_from(["0.5,1", "1", "0.1,1", "x", ",", "", "nan,1"])),
        st.tuples(st.just("--executor"), st.sampled_from(["local", "dask", "slurm", ""])),
        st.tuples(st.just("--scheduler"), st.sampled_from(["tcp://127.0.0.1:8786", "", " "])),
        st.tuples(st.just("--cell"), st.sampled_from(["ideal", "real", "ideal,real", ",", "lab"])),
    ),
    max_size=3,
)
CLI_EXAMPLES = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@CLI_EXAMPLES
@given(options=run_options)
def test_generated_run_options_simulate_or_are_refused_in_one_line(options) -> None:
    argv = ["run", SINGLE, *[part for option in options for part in option]]
    code, _, err = call(argv)
    if code != "simulated":
        assert_refused(code, err)


@CLI_EXAMPLES
@given(options=experiment_options)
def test_generated_experiment_options_run_trials_or_are_refused_in_one_line(options, tmp_path_factory) -> None:
    out = tmp_path_factory.mktemp("experiment")
    argv = ["experiment", "--out", str(out), *[part for option in options for part in option]]
    code, _, err = call(argv)
    if code != "simulated":
        assert_refused(code, err)


# -- plan files (.toml): every mistake names the file, the entry and the problem ---------------

GOOD_PLAN = """
[objects.bar]
size_mm = [80, 40, 40]

[colours.orange]
rgb = [1.0, 0.5, 0.0]

[[targets]]
object = "bar"
colour = "orange"
x_mm = 500
y_mm = -150
"""

BAD_PLANS = {
    "not toml": ("targets = [", "not TOML"),
    "unknown top key": ("threshold = 1\n" + GOOD_PLAN, "the top level: unknown key 'threshold'"),
    "unknown target key": (
        GOOD_PLAN.replace("x_mm = 500", 'x_mm = 500\ncolor = "red"'),
        "[[targets]] 1: unknown key 'color'",
    ),
    "unknown object key": (GOOD_PLAN.replace("size_mm", "size"), "[objects.bar]: unknown key 'size'"),
    "cannot span": (GOOD_PLAN.replace("[80, 40, 40]", "[100, 90, 40]"), "no horizontal side the gripper can span"),
    "colour without rgb": (GOOD_PLAN.replace("rgb = [1.0, 0.5, 0.0]", ""), "[colours.orange]: a colour needs rgb"),
    "unknown colour": (GOOD_PLAN.replace('colour = "orange"', 'colour = "teal"'), 'unknown colour "teal"'),
    "unknown type": (GOOD_PLAN.replace('object = "bar"', 'object = "beam"'), 'unknown object type "beam"'),
    "negative size": (GOOD_PLAN.replace("[80, 40, 40]", "[80, -40, 40]"), "has an edge that is not positive"),
    "size not a number": (GOOD_PLAN.replace("[80, 40, 40]", '[80, "40", 40]'), 'size_mm = "40" is not a number'),
    "missing coordinate": (GOOD_PLAN.replace("y_mm = -150", ""), "[[targets]] 1: missing y_mm"),
    "out of reach": (GOOD_PLAN.replace("x_mm = 500", "x_mm = 1500"), "out of reach"),
}


@pytest.mark.parametrize("command", ["run", "show"])
@pytest.mark.parametrize("case", sorted(BAD_PLANS))
def test_a_bad_plan_file_is_one_line_naming_the_file_and_entry(tmp_path: Path, command: str, case: str) -> None:
    text, fragment = BAD_PLANS[case]
    path = tmp_path / "plan.toml"
    path.write_text(text)
    code, _, err = call([command, str(path)])
    line = assert_refused(code, err)
    assert str(path) in line and fragment in line, line


def test_a_good_plan_file_reaches_the_world(tmp_path: Path) -> None:
    path = tmp_path / "plan.toml"
    path.write_text(GOOD_PLAN)
    code, _, err = call(["run", str(path)])
    assert code == "simulated", err


plan_values = st.one_of(
    st.integers(-200, 900),
    st.floats(allow_nan=True),
    st.text(max_size=4),
    st.booleans(),
    st.lists(st.integers(-50, 120), max_size=4),
)
plan_keys = st.sampled_from(["object", "colour", "x_mm", "y_mm", "yaw_deg", "name", "size_mm", "rgb", "seed", "colr"])


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(
    edits=st.dictionaries(plan_keys, plan_values, max_size=3),
    size=st.lists(st.integers(-20, 120), min_size=0, max_size=4),
)
def test_a_generated_plan_file_runs_or_is_refused_by_the_contract(tmp_path: Path, edits: dict, size: list) -> None:
    def toml(value: object) -> str:
        if isinstance(value, bool):
            return "true" if value else "false"
        if isinstance(value, str):
            return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(value, float) and value != value:
            return "nan"
        if isinstance(value, list):
            return "[" + ", ".join(toml(v) for v in value) + "]"
        return (
            repr(value)
            if not isinstance(value, float) or abs(value) != float("inf")
            else ("inf" if value > 0 else "-inf")
        )

    target = {"object": "bar", "colour": "orange", "x_mm": 500, "y_mm": -150, **edits}
    lines = [f"[objects.bar]\nsize_mm = {toml(size)}", "[colours.orange]\nrgb = [1.0, 0.5, 0.0]", "[[targets]]"]
    lines += [f"{key} = {toml(value)}" for key, value in target.items()]
    path = tmp_path / "generated.toml"
    path.write_text("\n".join(lines) + "\n")
    code, _, err = call(["run", str(path)])
    if code != "simulated":
        line = assert_refused(code, err)
        assert str(path) in line, line


# ----------------------------------------------------------------------------------------------
# Generated XML trees and cell files: accepted, or one line and exit 2, never a traceback
# ----------------------------------------------------------------------------------------------

xml_tags = st.sampled_from(
    ["Sequence", "Fallback", "ReactiveSequence", "Parallel", "Inverter", "Repeat", "RetryUntilSuccessful",
     "AlwaysSuccess", "AlwaysFailure", "SetBlackboardVariable", "Sequense", "Detect", "RetryUntilThreshold"]
)  # fmt: skip
xml_attributes = st.dictionaries(
    st.sampled_from(["name", "num_cycles", "num_attempts", "success_count", "key", "value", "obj", "bogus"]),
    st.one_of(st.text(max_size=6), st.sampled_from(["3", "-1", "1e9", "{x}", "red", "0.5,0,0", "nan"])),
    max_size=2,
)
xml_nodes = st.recursive(
    st.tuples(xml_tags, xml_attributes, st.just(())) | st.tuples(st.just("SubTree"), st.fixed_dictionaries(
        {"ID": st.sampled_from(["A", "B", "C", "Z"])}), st.just(())),
    lambda children: st.tuples(xml_tags, xml_attributes, st.lists(children, max_size=3)),
    max_leaves=12,
)  # fmt: skip


def _xml_text(node: tuple) -> str:
    from xml.sax.saxutils import quoteattr

    tag, attributes, children = node
    attrs = "".join(f" {key}={quoteattr(value)}" for key, value in attributes.items())
    inner = "".join(_xml_text(child) for child in children)
    return f"<{tag}{attrs}>{inner}</{tag}>" if inner else f"<{tag}{attrs}/>"


@settings(
    max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(trees=st.dictionaries(st.sampled_from(["A", "B", "C"]), xml_nodes, min_size=1, max_size=3), main=st.booleans())
def test_a_generated_xml_tree_is_drawn_or_refused_by_the_contract(tmp_path: Path, trees: dict, main: bool) -> None:
    body = "".join(f'<BehaviorTree ID="{tree_id}">{_xml_text(node)}</BehaviorTree>' for tree_id, node in trees.items())
    chosen = f' main_tree_to_execute="{next(iter(trees))}"' if main else ""
    path = tmp_path / "generated.xml"
    path.write_text(f'<root BTCPP_format="4"{chosen}>{body}</root>')
    code, _, err = call(["show", str(path)])
    if code != 0:
        line = assert_refused(code, err)
        assert str(path) in line, line


cell_values = st.one_of(
    st.integers(-5, 5),
    st.floats(allow_nan=True),
    st.text(max_size=4),
    st.booleans(),
    st.lists(st.integers(), max_size=2),
)


@settings(
    max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture]
)
@given(
    top=st.dictionaries(st.sampled_from(["preset", "cell_seed", "run_seed", "bogus"]), cell_values, max_size=2),
    tables=st.dictionaries(
        st.sampled_from(["kinematics", "joints", "camera", "imaging", "gripper", "objects", "friction", "nope"]),
        st.dictionaries(
            st.sampled_from(["enabled", "coupling_erp", "joint_sigma_mrad", "distortion_k1", "edge_sigma_mm", "spread",
                             "blur_sigma_px", "bogus"]), cell_values,
            max_size=3,
        ),
        max_size=3,
    ),
)  # fmt: skip
def test_a_generated_cell_file_runs_or_is_refused_by_the_contract(tmp_path: Path, top: dict, tables: dict) -> None:
    def toml(value: object) -> str:
        if isinstance(value, bool):
            return "true" if value else "false"
        if isinstance(value, str):
            return json.dumps(value)
        if isinstance(value, float):
            return (
                "nan"
                if value != value
                else ("inf" if value == float("inf") else "-inf" if value < -1e308 else repr(value))
            )
        if isinstance(value, list):
            return "[" + ", ".join(toml(v) for v in value) + "]"
        return repr(value)

    lines = [f"{key} = {toml(value)}" for key, value in top.items()]
    for name, table in tables.items():
        lines.append(f"[{name}]")
        lines += [f"{key} = {toml(value)}" for key, value in table.items()]
    path = tmp_path / "cell.toml"
    path.write_text("\n".join(lines) + "\n")
    code, _, err = call(["run", SINGLE, "--cell", str(path)])
    if code != "simulated":
        line = assert_refused(code, err)
        assert "cell" in line, line
