"""Measured flux maps (mctools.fluxmap), and the simulator's reader against it on the same files.

Every refusal of the format (docs/machine-models.md "Measured flux maps") is checked here for the
Python reader (file, line and reason in the message); the same files go through the simulator's
reader (`fluxmap-check`, sim/tools/fluxmap_check.cpp), which must refuse them with exit status 2 and
the identical message, and, for good maps, derive the same figures. The C++ side is looked up in
$MCSIM_TOOLS_DIR, then build/host/sim/tools; without it those comparisons skip.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
from pathlib import Path

import numpy as np
import pytest

from mctools.fluxmap import FluxMapError, read_flux_map
from mctools.preset import PresetError, export_map, load_preset

REPO = Path(__file__).resolve().parents[2]
HEADER = "i_d_A,i_q_A,psi_d_Vs,psi_q_Vs"


def _tool(name: str) -> Path | None:
    dirs = []
    env = os.environ.get("MCSIM_TOOLS_DIR")
    if env:
        dirs.append(Path(env) if Path(env).is_absolute() else REPO / env)
    dirs.append(REPO / "build" / "host" / "sim" / "tools")
    for d in dirs:
        if (d / name).is_file() and os.access(d / name, os.X_OK):
            return d / name
    return None


FLUXMAP_CHECK = _tool("fluxmap-check")
needs_cpp = pytest.mark.skipif(FLUXMAP_CHECK is None, reason="fluxmap-check not built (build/host/sim/tools)")


def linear(i_d, i_q):
    """A reciprocal map with cross-coupling: psi = psi_pm + L i, L symmetric."""
    return 0.3 + 0.010 * i_d + 0.001 * i_q, 0.001 * i_d + 0.02 * i_q


def map_rows(f=linear, ds=(-2, -1, 0, 1, 2), qs=(-3, 0, 3)):
    return [f"{d},{q},{f(d, q)[0]!r},{f(d, q)[1]!r}" for d in ds for q in qs]


def write(tmp_path, name, lines, header=HEADER):
    p = tmp_path / name
    p.write_text("\n".join(([header] if header is not None else []) + lines) + "\n")
    return p


def bad_maps(tmp_path):
    """(file, expected line or None, substring of the reason)."""
    good = map_rows()
    out = []
    out.append((write(tmp_path, "header.csv", good, header="i_d_A,i_q_A,psi_d_Wb,psi_q_Wb"), 1, "is not"))
    out.append((write(tmp_path, "ragged.csv", good[:4] + ["0,0,0.3"] + good[5:]), 6, "expected 4 columns"))
    out.append((write(tmp_path, "ragged5.csv", good[:2] + [good[2] + ",1"] + good[3:]), 4, "got 5"))
    out.append((write(tmp_path, "nan.csv", good[:7] + ["0,0,nan,0"] + good[8:]), 9, "is not a finite number"))
    out.append((write(tmp_path, "inf.csv", good[:7] + ["0,0,1e999,0"] + good[8:]), 9, "not a finite number"))
    out.append((write(tmp_path, "text.csv", good[:3] + ["-1,-3,abc,0"] + good[4:]), 5, "'abc' is not"))
    out.append((write(tmp_path, "dup.csv", good + [good[7]]), 17, "duplicate grid point"))
    out.append((write(tmp_path, "missing.csv", good[:10] + good[11:]), None, "no row for grid point"))
    out.append((write(tmp_path, "offgrid.csv", map_rows(ds=(-2, -1, 0, 1.5, 2))), 11, "off the equally spaced grid"))
    out.append((write(tmp_path, "two.csv", map_rows(qs=(-3, 3))), None, "at least 3 grid points"))
    nd = map_rows(lambda d, q: (0.3 - 0.02 * (d == 1) + 0.01 * d, 0.02 * q))
    out.append((write(tmp_path, "mono_d.csv", nd), 11, "does not rise with i_d"))
    nq = map_rows(lambda d, q: (0.3 + 0.01 * d, 0.02 * q * (-1 if d == 2 else 1)))
    out.append((write(tmp_path, "mono_q.csv", nq), 15, "does not rise with i_q"))
    out.append((write(tmp_path, "no_pm.csv", map_rows(lambda d, q: (-0.05 + 0.01 * d, 0.02 * q))), None,
                "no PM flux on +d"))
    out.append((write(tmp_path, "no_zero.csv", map_rows(ds=(1, 2, 3, 4))), None, "does not contain i = 0"))
    out.append((write(tmp_path, "empty.csv", [], header=None), None, "empty file"))
    return out


def test_each_refusal_names_file_line_and_reason(tmp_path):
    for path, line, reason in bad_maps(tmp_path):
        with pytest.raises(FluxMapError) as e:
            read_flux_map(path)
        msg = str(e.value)
        prefix = f"{path}:{line}: " if line is not None else f"{path}: "
        assert msg.startswith(prefix), (path.name, msg)
        assert reason in msg, (path.name, msg)


@needs_cpp
def test_cpp_reader_refuses_the_same_files_with_the_same_message(tmp_path):
    for path, _, _ in bad_maps(tmp_path):
        with pytest.raises(FluxMapError) as e:
            read_flux_map(path)
        p = subprocess.run([str(FLUXMAP_CHECK), str(path)], capture_output=True, text=True, timeout=30)
        assert p.returncode == 2, (path.name, p.stdout, p.stderr)
        assert p.stderr.strip() == str(e.value), path.name


def test_good_map_derived_figures_exact_for_a_linear_map(tmp_path):
    # rows in a shuffled order, comments and blank lines: allowed
    rows = map_rows()
    rows = rows[7:] + ["# a comment", ""] + rows[:7]
    m = read_flux_map(write(tmp_path, "lin.csv", rows))
    assert (m.x.n, m.y.n) == (5, 3)
    assert m.psi_pm == pytest.approx(0.3, rel=1e-15)
    assert m.ld == pytest.approx(0.010, rel=1e-12)
    assert m.lq == pytest.approx(0.02, rel=1e-12)
    assert m.ldq == pytest.approx(0.001, rel=1e-12)
    assert m.recip_max < 1e-12 and m.warnings == []
    # bilinear reproduces a linear map everywhere, also outside the grid (linear continuation)
    for i_d, i_q in [(0.3, 0.7), (-2, 3), (5.0, -7.0), (-9.0, 9.0)]:
        pd, pq = m.flux(i_d, i_q)
        assert (float(pd), float(pq)) == pytest.approx(linear(i_d, i_q), abs=1e-14)


def test_non_reciprocal_map_warns_never_refuses(tmp_path):
    # d psi_d/d i_q = 0.004, d psi_q/d i_d = 0: 0.004/sqrt(0.01*0.02) = 28 % mismatch
    m = read_flux_map(write(tmp_path, "nr.csv", map_rows(lambda d, q: (0.3 + 0.01 * d + 0.004 * q, 0.02 * q))))
    assert m.recip_max == pytest.approx(0.004 / math.sqrt(0.01 * 0.02), rel=1e-9)
    assert m.recip_rms == pytest.approx(m.recip_max, rel=1e-9)
    assert len(m.warnings) == 1 and "reciprocity" in m.warnings[0]


def _cpp_figures(path):
    p = subprocess.run([str(FLUXMAP_CHECK), str(path)], capture_output=True, text=True, timeout=30)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@needs_cpp
def test_cpp_and_python_derive_the_same_figures(tmp_path):
    sun = tmp_path / "sun.csv"
    export_map(load_preset("sun2016-ipm-5kw"), sun, 41, None)
    files = [REPO / "presets" / "baldor-5p6kw-pmsyrm.csv", sun,
             write(tmp_path, "lin.csv", map_rows()),
             write(tmp_path, "nr.csv", map_rows(lambda d, q: (0.3 + 0.01 * d + 0.004 * q, 0.02 * q)))]
    for f in files:
        c = _cpp_figures(f)
        m = read_flux_map(f)
        py = {"n_d": m.x.n, "n_q": m.y.n, "i_d_lo": m.x.lo, "i_d_hi": m.x.hi, "i_q_lo": m.y.lo,
              "i_q_hi": m.y.hi, "psi_pm": m.psi_pm, "psi_q0": m.psi_q0, "ld": m.ld, "lq": m.lq,
              "ldq": m.ldq, "recip_rms": m.recip_rms, "recip_max": m.recip_max,
              "recip_max_id": m.recip_max_at[0], "recip_max_iq": m.recip_max_at[1]}
        for k, v in py.items():
            # same formulas in the same order: round-off only (the rms sums in another order)
            assert c[k] == pytest.approx(v, rel=1e-12, abs=1e-15), (f.name, k, c[k], v)
        assert c["warnings"] == m.warnings, f.name


def test_baldor_preset_values_from_the_map():
    m = load_preset("baldor-5p6kw-pmsyrm")
    assert m.pole_pairs == 2
    assert m.psi_pm_wb == pytest.approx(0.44414573760687304, rel=1e-15)   # the (0, 0) node
    # central differences over +-2 A at i = 0, from the map's nodes
    fm = m.model
    assert m.ld_h == pytest.approx((fm.psi_d[11, 13] - fm.psi_d[9, 13]) / 4, rel=1e-12)
    assert m.lq_h == pytest.approx((fm.psi_q[10, 14] - fm.psi_q[10, 12]) / 4, rel=1e-12)
    assert 0.02 < m.ld_h < 0.03 and 0.1 < m.lq_h < 0.2   # a PM-SyRM: Lq >> Ld near i = 0
    assert fm.warnings == []   # 1.0 % rms, 5.9 % max reciprocity mismatch: under the 10 % level


def test_export_map_round_trip_reproduces_the_small_signal_values(tmp_path):
    src = load_preset("sun2016-ipm-5kw")
    out = tmp_path / "sun.csv"
    export_map(src, out, 41, None)
    m = read_flux_map(out)
    psi_pm, ld, lq = src.small_signal()
    assert m.psi_pm == pytest.approx(psi_pm, rel=1e-12)   # i = 0 is a node of the odd grid
    # central differences of +-1 A on a saturating model: second-order error, < 0.5 %
    assert m.ld == pytest.approx(ld, rel=5e-3)
    assert m.lq == pytest.approx(lq, rel=5e-3)
    # the map reproduces the model at its nodes and interpolates between them
    i_d, i_q = np.meshgrid(np.linspace(-13, 13, 7), np.linspace(-13, 13, 7))
    a = np.array(src.model.flux(i_d, i_q))
    b = np.array(m.flux(i_d, i_q))
    assert np.max(np.abs(a - b)) < 2e-3


def test_preset_with_both_models_or_a_bad_map_is_refused(tmp_path):
    lin = write(tmp_path, "lin.csv", map_rows())
    base = ('name = "x"\npole_pairs = 2\nrs_ohm = 0.1\ninertia_kgm2 = 0.01\nfriction_nms = 0\n'
            'i_rated_peak_a = 2\ntorque_rated_nm = 1\nvdc_nominal_v = 48\nf_sample_hz = 10000\n')
    both = tmp_path / "both.toml"
    both.write_text(base + '[flux_map]\nfile = "lin.csv"\n[saturation]\na_d0 = 1\na_q0 = 1\ni_f = 1\n')
    with pytest.raises(PresetError, match="either"):
        load_preset(str(both))
    bad = tmp_path / "bad.toml"
    write(tmp_path, "nan.csv", map_rows()[:3] + ["0,0,nan,0"] + map_rows()[4:])
    bad.write_text(base + '[flux_map]\nfile = "nan.csv"\n')
    with pytest.raises(PresetError, match=r"nan\.csv:5: column psi_d_Vs"):
        load_preset(str(bad))
    good = tmp_path / "good.toml"
    good.write_text(base + 'ld_h = 0.02\n[flux_map]\nfile = "' + str(lin) + '"\n')   # absolute path
    m = load_preset(str(good))
    assert m.ld_h == 0.02 and m.lq_h == pytest.approx(0.02) and m.psi_pm_wb == pytest.approx(0.3)


@pytest.mark.skipif(not (REPO / "build/host/sim/app/mcsim").is_file(), reason="mcsim not built")
def test_mcsim_refuses_a_bad_map_preset_with_exit_2(tmp_path):
    write(tmp_path, "dup.csv", map_rows() + [map_rows()[3]])
    (tmp_path / "p.toml").write_text(
        'name = "x"\npole_pairs = 2\nrs_ohm = 0.1\ninertia_kgm2 = 0.01\nfriction_nms = 0\n'
        'i_rated_peak_a = 2\ntorque_rated_nm = 1\nvdc_nominal_v = 48\nf_sample_hz = 10000\n'
        '[flux_map]\nfile = "dup.csv"\n')
    p = subprocess.run([str(REPO / "build/host/sim/app/mcsim"), "check", str(REPO / "scenarios/sensorless_demo.toml"),
                        "--set", f"machine.preset={tmp_path / 'p.toml'}"], capture_output=True, text=True,
                       timeout=60)
    assert p.returncode == 2
    assert "flux_map.file" in p.stderr and "dup.csv:17: duplicate grid point" in p.stderr
