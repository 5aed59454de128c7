import json

import numpy as np
import pytest

from conftest import png_size, synthetic_columns, write_trace
from mctools import cli
from mctools.plot import OVERVIEW_HEAD_IN, OVERVIEW_ROW_IN, PANEL_HEIGHT_IN, WIDTH_IN
from mctools.trace import TraceError, break_wraps, load_trace, wrap_deg

DPI = 50  # small figures keep the tests light


def run(argv, capsys):
    rc = cli.main(argv)
    out, err = capsys.readouterr()
    return rc, out, err


def test_plot_full_trace_writes_all_panels(full_trace, tmp_path, capsys):
    out_dir = tmp_path / "png"
    rc, out, err = run(["plot", str(full_trace), "--out", str(out_dir), "--dpi", str(DPI)], capsys)
    assert rc == 0, err
    paths = [p for p in out.split("\n") if p]
    names = sorted(p.rsplit("/", 1)[-1] for p in paths)
    assert names == sorted(f"trace_{k}.png" for k in
                           ("overview", "angle", "angle_err", "speed", "current", "torque"))
    for p in paths:
        path = out_dir / p.rsplit("/", 1)[-1]
        assert path.stat().st_size > 1000
        w, h = png_size(path)
        assert w == round(WIDTH_IN * DPI)
        if path.name.endswith("overview.png"):
            assert h == round((OVERVIEW_HEAD_IN + 5 * OVERVIEW_ROW_IN) * DPI)
        else:
            assert h == round(PANEL_HEIGHT_IN * DPI)


def test_plot_defaults_to_trace_directory(full_trace, capsys):
    rc, out, _ = run(["plot", str(full_trace), "--dpi", str(DPI)], capsys)
    assert rc == 0
    assert (full_trace.parent / "trace_overview.png").is_file()


def test_missing_columns_skip_panels(tmp_path, capsys):
    cols = synthetic_columns(n=300)
    # Old-style trace: no estimator columns, no torque; an unknown extra column is fine.
    cols["newton_iter"] = np.ones(300)
    keep = ["t_s", "theta_deg", "speed_rpm", "speed_ref_rpm", "id_a", "iq_a", "newton_iter"]
    trace = write_trace(tmp_path / "old.csv", cols, keep)
    rc, out, err = run(["plot", str(trace), "--out", str(tmp_path), "--dpi", str(DPI)], capsys)
    assert rc == 0, err
    names = {p.rsplit("/", 1)[-1] for p in out.split()}
    assert names == {"old_overview.png", "old_angle.png", "old_speed.png", "old_current.png"}
    w, h = png_size(tmp_path / "old_overview.png")
    assert h == round((OVERVIEW_HEAD_IN + 3 * OVERVIEW_ROW_IN) * DPI)


def test_angle_error_derived_when_column_absent(tmp_path, capsys):
    cols = synthetic_columns(n=300)
    trace = write_trace(tmp_path / "t.csv", cols, ["t_s", "theta_deg", "theta_hat_deg"])
    rc, out, _ = run(["plot", str(trace), "--out", str(tmp_path), "--dpi", str(DPI)], capsys)
    assert rc == 0
    assert (tmp_path / "t_angle_err.png").is_file()


def test_metrics_annotation(full_trace, tmp_path, capsys):
    metrics = tmp_path / "metrics.json"
    metrics.write_text(json.dumps({"passed": True, "angle_err_rms_deg": 1.234,
                                   "nested": {"speed_err_max_rpm": 7}, "note": "text"}))
    rc, out, err = run(["plot", str(full_trace), "--out", str(tmp_path / "m"), "--dpi", str(DPI),
                        "--title", "startup", "--metrics", str(metrics)], capsys)
    assert rc == 0, err
    from mctools.plot import headline_metrics
    head = headline_metrics(json.loads(metrics.read_text()))
    assert head[0] == "passed: yes"
    assert "angle_err_rms_deg = 1.234" in head
    # nested (per-window) figures only when named
    assert not any(h.startswith("nested.") for h in head)
    assert headline_metrics(json.loads(metrics.read_text()), keys=["nested.speed_err_max_rpm"]) == \
        ["nested.speed_err_max_rpm = 7"]


@pytest.mark.parametrize("content, needle", [
    (None, "no such file"),
    ("", "empty"),
    ("t_s,theta_deg\n", "no data rows"),
    ("time,theta_deg\n0,1\n", "no 't_s' column"),
    ("t_s,theta_deg\n0,abc\n1,2\n", "cannot parse"),
])
def test_bad_input_exit_2(tmp_path, capsys, content, needle):
    path = tmp_path / "bad.csv"
    if content is not None:
        path.write_text(content)
    rc, out, err = run(["plot", str(path), "--out", str(tmp_path)], capsys)
    assert rc == 2
    assert needle in err
    assert "bad.csv" in err
    assert not list(tmp_path.glob("*.png"))


def test_bad_metrics_exit_2(full_trace, tmp_path, capsys):
    bad = tmp_path / "m.json"
    bad.write_text("{not json")
    rc, _, err = run(["plot", str(full_trace), "--metrics", str(bad)], capsys)
    assert rc == 2 and "not valid JSON" in err


def test_only_time_column_exit_2(tmp_path, capsys):
    path = tmp_path / "t.csv"
    path.write_text("t_s,state\n0,1\n1,1\n")
    rc, _, err = run(["plot", str(path)], capsys)
    assert rc == 2 and "none of the plotted columns" in err


def test_truncated_last_line_is_dropped(tmp_path, capsys):
    path = tmp_path / "t.csv"
    path.write_text("t_s,speed_rpm\n0,1\n0.1,2\n0.2")
    tr = load_trace(path)
    assert len(tr) == 2
    assert "incomplete last line" in capsys.readouterr().err


def test_comment_lines_and_spaces_in_header(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("# mcsim v0\nt_s, speed_rpm\n0, 1\n0.1, 2\n")
    tr = load_trace(path)
    np.testing.assert_allclose(tr["speed_rpm"], [1, 2])


def test_subprocess_module_entry(full_trace, tmp_path):
    import subprocess
    import sys
    r = subprocess.run([sys.executable, "-m", "mctools", "plot", str(tmp_path / "nope.csv")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "no such file" in r.stderr


# -- wrap handling ------------------------------------------------------------------

def test_break_wraps_inserts_nan_at_each_wrap():
    t = np.arange(8.0)
    a = np.array([150.0, 170.0, -170.0, -150.0, 179.0, -179.0, -178.0, -177.0])
    # Wraps between samples 1-2 (+180 -> -180), 3-4 (-150 -> 179, backwards) and 4-5.
    tt, aa = break_wraps(t, a)
    nan = np.flatnonzero(np.isnan(aa))
    assert len(nan) == 3
    assert len(tt) == len(aa) == len(a) + 3
    np.testing.assert_array_equal(aa[~np.isnan(aa)], a)
    assert np.all(np.diff(tt) > 0)  # time stays monotonic
    np.testing.assert_allclose(tt[nan], [1.5, 3.5, 4.5])


def test_break_wraps_no_wrap_is_identity():
    t = np.linspace(0, 1, 50)
    a = 100 * np.sin(t)
    tt, aa = break_wraps(t, a)
    np.testing.assert_array_equal(tt, t)
    np.testing.assert_array_equal(aa, a)
    tt, aa = break_wraps(t[:1], a[:1])
    assert len(tt) == 1


def test_break_wraps_on_rotating_angle():
    t = np.linspace(0, 1, 10001)
    a = wrap_deg(360.0 * 7.25 * t)  # 7.25 turns: 7 wraps
    _, aa = break_wraps(t, a)
    assert np.isnan(aa).sum() == 7


def test_wrap_deg_range():
    x = wrap_deg(np.array([-540.0, -180.0, 180.0, 359.0, 0.0]))
    np.testing.assert_allclose(x, [-180.0, -180.0, -180.0, -1.0, 0.0])


def test_headline_picks_named_and_top_level_figures():
    from mctools.plot import headline_metrics
    from mctools.trace import TraceError

    m = {"scenario": "x", "speed_err_steady_max_pct": 0.02, "current_peak_a": 13.2,
         "windows": {"steady": {"speed_err_max_pct": 0.5}}}
    auto = headline_metrics(m)
    assert all("windows" not in h for h in auto)
    named = headline_metrics(m, keys=["windows.steady.speed_err_max_pct", "current_peak_a"])
    assert named == ["windows.steady.speed_err_max_pct = 0.5", "current_peak_a = 13.2"]
    with pytest.raises(TraceError, match="no_such"):
        headline_metrics(m, keys=["no_such"])
