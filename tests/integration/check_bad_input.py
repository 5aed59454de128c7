#!/usr/bin/env python3
"""Malformed scenarios must be rejected before anything runs: exit status 2 and a message that
names the offending key (or the file). Each case: (args, text that must appear in stderr)."""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
GOOD = os.path.join(HERE, "..", "..", "scenarios", "speed_step_inertia.toml")


def cases():
    bad = lambda name: os.path.join(HERE, "bad", name)
    return [
        (["run", bad("unknown_key.toml")], "control.speed_ref_rmp"),
        (["run", bad("unknown_section.toml")], "controller"),
        (["run", bad("wrong_type.toml")], "scenario.duration_s"),
        (["run", bad("out_of_range.toml")], "control.ts_s"),
        (["run", bad("bad_enum.toml")], "mechanics.mode"),
        (["run", bad("bad_profile.toml")], "control.speed_ref_rpm"),
        (["run", bad("bad_window.toml")], "metrics.window"),
        (["run", bad("syntax.toml")], "TOML syntax error"),
        (["run", bad("does_not_exist.toml")], "cannot open scenario file"),
        (["run", bad("bad_preset.toml")], "machine.preset"),
        (["run", GOOD, "--set", "control.ts_s=1.0"], "control.ts_s"),
        (["run", GOOD, "--set", "sensors.adc_bitz=12"], "sensors.adc_bitz"),
        (["run", GOOD, "--set", "control.current_bw_hz=fast"], "control.current_bw_hz"),
        (["run", GOOD, "--set", "control.decouple=1"], "control.decouple"),
        (["run", GOOD, "--set", "sensors.i_gain_err=[0.1,0.2]"], "sensors.i_gain_err"),
    ]


def main():
    mcsim = sys.argv[1]
    failed = 0
    with tempfile.TemporaryDirectory() as out:
        for args, needle in cases():
            r = subprocess.run([mcsim] + args + ["--out", out, "--quiet"], capture_output=True, text=True)
            ran = os.path.exists(os.path.join(out, "metrics.json"))
            ok = r.returncode == 2 and needle in r.stderr and not ran
            print(f"{'ok  ' if ok else 'FAIL'}: {' '.join(args)} -> exit {r.returncode}: {r.stderr.strip()}")
            failed += 0 if ok else 1
    # and the good file with a valid --set passes validation
    r = subprocess.run([mcsim, "check", GOOD, "--set", "control.current_bw_hz=400"], capture_output=True, text=True)
    ok = r.returncode == 0
    print(f"{'ok  ' if ok else 'FAIL'}: check with a valid --set -> exit {r.returncode} {r.stderr.strip()}")
    failed += 0 if ok else 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
