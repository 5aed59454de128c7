import json
from pathlib import Path

import pytest

from mctools import cli
from fakes import SUN_PRESET_TOML
from mctools.preset import PresetError, derived_figures, find_preset, load_preset

REPO_PRESETS = Path(__file__).resolve().parents[2] / "presets"



@pytest.fixture
def preset_dir(tmp_path):
    d = tmp_path / "presets"
    d.mkdir()
    (d / "sun-test.toml").write_text(SUN_PRESET_TOML)
    return d


def test_preset_by_name_via_option(preset_dir, capsys):
    rc = cli.main(["preset", "sun-test", "--preset-dir", str(preset_dir)])
    out = capsys.readouterr().out
    assert rc == 0
    assert "964 rpm" in out
    assert "32.5" in out


def test_preset_by_name_via_env(preset_dir, monkeypatch, capsys):
    monkeypatch.setenv("MC_PRESET_DIR", str(preset_dir))
    rc = cli.main(["preset", "sun-test", "--json"])
    figs = json.loads(capsys.readouterr().out)
    assert rc == 0
    assert figs["mtpa_torque_nm"] == pytest.approx(32.5, abs=0.1)
    assert figs["base_speed_noload_rpm"] == pytest.approx(964, abs=1)
    assert figs["ld_model_h"] == pytest.approx(10.5e-3, rel=0.01)


def test_preset_by_path(preset_dir):
    m = load_preset(str(preset_dir / "sun-test.toml"))
    assert m.pole_pairs == 5 and m.model.a_dq == 1441.3


def test_preset_not_found_exit_2(tmp_path, capsys, monkeypatch):
    monkeypatch.delenv("MC_PRESET_DIR", raising=False)
    rc = cli.main(["preset", "no-such-machine", "--preset-dir", str(tmp_path)])
    err = capsys.readouterr().err
    assert rc == 2 and "no-such-machine" in err and str(tmp_path) in err
    rc = cli.main(["preset", str(tmp_path / "x.toml")])
    assert rc == 2 and "no such preset file" in capsys.readouterr().err


def test_malformed_preset_exit_2(tmp_path, capsys):
    (tmp_path / "bad.toml").write_text("name = \n")
    assert cli.main(["preset", str(tmp_path / "bad.toml")]) == 2
    assert "invalid TOML" in capsys.readouterr().err
    (tmp_path / "short.toml").write_text('name = "x"\npole_pairs = 2\n')
    assert cli.main(["preset", str(tmp_path / "short.toml")]) == 2
    assert "required" in capsys.readouterr().err


def test_preset_without_saturation_uses_linear_model(tmp_path):
    text = SUN_PRESET_TOML.split("[saturation]")[0]
    (tmp_path / "lin.toml").write_text(text)
    figs = derived_figures(load_preset(str(tmp_path / "lin.toml")))
    assert figs["ld_model_h"] == pytest.approx(10.5e-3, rel=1e-9)
    assert figs["psi_pm_model_wb"] == pytest.approx(0.34305, rel=1e-9)


@pytest.mark.skipif(not (REPO_PRESETS / "sun2016-ipm-5kw.toml").is_file(),
                    reason="repo preset not present")
def test_repo_presets_match_machines_md():
    sun = derived_figures(load_preset(str(find_preset("sun2016-ipm-5kw", REPO_PRESETS))))
    # a_dq, a_qq, a_q0 calibrated by `mctools fit-adq` (machines.md's original fit: 32.5 N m).
    assert sun["mtpa_torque_nm"] == pytest.approx(33.46, abs=0.1)
    assert sun["psi_pm_model_wb"] == pytest.approx(sun["psi_pm_preset_wb"], rel=0.01)
    assert sun["ld_model_h"] == pytest.approx(sun["ld_preset_h"], rel=0.01)
    assert sun["lq_model_h"] == pytest.approx(sun["lq_preset_h"], rel=0.01)
    if (REPO_PRESETS / "brodatzki-35kw.toml").is_file():
        b = derived_figures(load_preset("brodatzki-35kw", REPO_PRESETS))
        assert b["mtpa_torque_nm"] == pytest.approx(79.3, abs=0.2)
        assert b["ld_model_h"] == pytest.approx(b["ld_preset_h"], rel=0.01)
        assert b["lq_model_h"] == pytest.approx(b["lq_preset_h"], rel=0.01)
