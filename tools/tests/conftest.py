import struct
from pathlib import Path

import numpy as np
import pytest

FULL_COLUMNS = ["t_s", "theta_deg", "theta_hat_deg", "angle_err_deg", "speed_rpm", "speed_hat_rpm",
                "speed_ref_rpm", "id_a", "iq_a", "id_ref_a", "iq_ref_a", "ud_v", "uq_v",
                "torque_nm", "torque_ref_nm", "load_nm", "ia_a", "ib_a", "ic_a", "vdc_v", "state"]


def synthetic_columns(n=2000, ts=1e-4):
    """A plausible ramp-up run: speed ramps to 300 rpm, estimate lags a few degrees."""
    t = np.arange(n) * ts
    p = 5
    speed = np.minimum(t / 0.1, 1.0) * 300.0
    theta = np.cumsum(speed * 2 * np.pi / 60 * p) * ts
    err = 3.0 * np.sin(2 * np.pi * 5 * t)
    wrap = lambda a: (a + 180.0) % 360.0 - 180.0  # noqa: E731
    th = wrap(np.degrees(theta))
    cols = {
        "t_s": t, "theta_deg": th, "theta_hat_deg": wrap(th + err), "angle_err_deg": err,
        "speed_rpm": speed, "speed_hat_rpm": speed + 2 * np.sin(t * 50), "speed_ref_rpm": speed,
        "id_a": -0.5 + 0 * t, "iq_a": 5 + 0.1 * np.sin(t * 300), "id_ref_a": -0.5 + 0 * t,
        "iq_ref_a": 5 + 0 * t, "ud_v": 0 * t, "uq_v": 50 + 0 * t, "torque_nm": 12 + 0 * t,
        "torque_ref_nm": 12 + 0 * t, "load_nm": 10 + 0 * t, "ia_a": np.cos(theta),
        "ib_a": np.cos(theta - 2.1), "ic_a": np.cos(theta + 2.1), "vdc_v": 300 + 0 * t,
        "state": np.full(n, 4.0),
    }
    return cols


def write_trace(path: Path, cols: dict, columns=None):
    columns = list(columns or cols)
    data = np.column_stack([cols[c] for c in columns])
    fmt = ["%d" if c == "state" else "%.9g" for c in columns]
    np.savetxt(path, data, delimiter=",", header=",".join(columns), comments="", fmt=fmt)
    return path


def png_size(path: Path):
    """(width, height) from the PNG signature and IHDR chunk."""
    with open(path, "rb") as f:
        head = f.read(24)
    assert head[:8] == b"\x89PNG\r\n\x1a\n", f"{path} is not a PNG"
    assert head[12:16] == b"IHDR"
    return struct.unpack(">II", head[16:24])


@pytest.fixture
def full_trace(tmp_path):
    return write_trace(tmp_path / "trace.csv", synthetic_columns())
