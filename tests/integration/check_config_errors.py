#!/usr/bin/env python3
"""The drive's configuration is validated by the firmware's parameter table (mc_drive_build) and a
refusal reaches the user as exit 2 naming the scenario keys behind it, their values and the range;
`mcsim check` refuses the same as `mcsim run`, before anything runs."""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
SCN = os.path.join(HERE, "..", "..", "scenarios")
SUN = os.path.join(SCN, "speed_step_inertia.toml")
BRO = os.path.join(SCN, "brodatzki", "torque_steps_0rpm.toml")

CASES = [
    # the current sensor's span below the over-current trip (+10 %): both keys named
    ([SUN, "--set", "sensors.i_full_scale_a=15"], ("sensors.i_full_scale_a", "control.i_trip_a", "19.935")),
    ([SUN, "--set", "control.i_trip_a=30"], ("sensors.i_full_scale_a", "control.i_trip_a", "= 30")),
    # the case: brodatzki-35kw with a 25 A sensor against its derived 240 A trip
    ([BRO, "--set", "sensors.i_full_scale_a=25"], ("sensors.i_full_scale_a", "= 25", "control.i_trip_a", "= 240")),
    ([SUN, "--set", "control.i_max_a=25", "--set", "control.i_trip_a=20"], ("control.i_max_a", "control.i_trip_a")),
    ([SUN, "--set", "sensors.vdc_full_scale_v=400"], ("sensors.vdc_full_scale_v", "control.vdc_max_v", "= 450")),
    ([SUN, "--set", "control.current_bw_hz=900"], ("control.current_bw_hz", "control.ts_s")),
    ([SUN, "--set", "startup.init_pos=\"three_step\""],
     ("startup.init_pos' = \"three_step\"", "control.angle_source' = \"encoder\"")),
    # the estimator's map over a span the plant's magnetics cannot be tabulated on (was exit 1)
    ([os.path.join(SCN, "sensorless_demo.toml"), "--set", "estimator.map_span_a=5000"], ("estimator.map_span_a", "5000")),
    ([SUN, "--set", "startup.step3_hold_s=1e-4"], ("startup.step3_hold_s",)),
]


def main():
    mcsim = sys.argv[1]
    failed = 0
    for args in CASES:
        for cmd in ("check", "run"):
            with tempfile.TemporaryDirectory() as out:
                extra = ["--out", out, "--quiet"] if cmd == "run" else []
                r = subprocess.run([mcsim, cmd] + args[0] + extra, capture_output=True, text=True, timeout=120)
                missing = [n for n in args[1] if n not in r.stderr]
                ran = os.path.exists(os.path.join(out, "metrics.json"))
                ok = r.returncode == 2 and not missing and not ran
                print(f"{'ok  ' if ok else 'FAIL'}: {cmd} {' '.join(args[0][1:])} -> exit {r.returncode}"
                      f"{' missing ' + str(missing) if missing else ''}: {r.stderr.strip()[:300]}")
                failed += 0 if ok else 1
    print(f"{len(CASES) * 2 - failed} passed, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
