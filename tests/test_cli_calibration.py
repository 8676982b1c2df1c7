"""The command line's calibration options: a bad file is one line naming the field, before anything moves."""

from __future__ import annotations

from bt_arrange import cli


def _bad_file(tmp_path):  # noqa: ANN001, ANN202
    path = tmp_path / "camera.toml"
    path.write_text(
        'cell = "real"\ndate = "today"\nwidth_px = 1920\nheight_px = 1080\nfx_px = -1\nfy_px = 1371\n'
        "cx_px = 959.5\ncy_px = 539.5\ndistortion = [0, 0, 0, 0, 0]\nreprojection_error_px = 0.1\nviews = 20\n"
        "[camera_to_base]\nx_mm = 500\ny_mm = 0\nz_mm = 700\nroll_deg = 180\npitch_deg = 0\nyaw_deg = -93\n"
    )
    return path


def test_run_with_a_bad_calibration_file_is_one_line_naming_the_field(tmp_path, capsys) -> None:
    code = cli.main(["run", "four_cubes", "--calibration", str(_bad_file(tmp_path))])
    err = capsys.readouterr().err
    assert code == 2
    assert "--calibration" in err and "fx_px = -1 must be positive" in err and err.count("\n") == 1


def test_experiment_with_a_bad_calibration_file_is_one_line_naming_the_field(tmp_path, capsys) -> None:
    code = cli.main(["experiment", "--trials", "1", "--calibration", str(_bad_file(tmp_path)), "--out", str(tmp_path)])
    err = capsys.readouterr().err
    assert code == 2
    assert "fx_px" in err and err.strip().count("\n") == 0, err


def test_run_with_a_missing_calibration_file_is_one_line(tmp_path, capsys) -> None:
    code = cli.main(["run", "four_cubes", "--calibration", str(tmp_path / "none.toml")])
    err = capsys.readouterr().err
    assert code == 2 and "cannot read the calibration file" in err


def test_a_real_cell_on_its_nominal_camera_is_named_in_one_line(capsys) -> None:
    from pathlib import Path

    from bt_arrange.cli_common import _note_uncalibrated

    _note_uncalibrated("ideal,real", None)
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "uncalibrated" in lines[0] and "bt-arrange calibrate --cell real" in lines[0]
    _note_uncalibrated("real", Path("camera.toml"))
    _note_uncalibrated("ideal", None)
    assert capsys.readouterr().err == ""
