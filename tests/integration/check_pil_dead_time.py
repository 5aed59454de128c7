#!/usr/bin/env python3
"""The dead-time floor on a target: `mcsim run S --pil IMAGE --set inverter.dead_time_s=X` writes X
as hw.dead_time_s into the image's configuration area; the image must refuse to boot for 0 and for
a value below its port's floor (hal_board_min_dead_time_s: 200 ns on both ports), naming
hw.dead_time_s, and boot for one at the floor. The host simulator (no floor: its ideal inverter)
is untouched by this."""
import argparse
import os
import subprocess
import sys
import tempfile


def run(mcsim, scenario, image, dt):
    out = os.path.join(tempfile.gettempdir(), "pil_dead_time")
    p = subprocess.run([mcsim, "run", scenario, "--quiet", "--out", out, "--pil", image,
                        "--set", f"inverter.dead_time_s={dt}"],
                       capture_output=True, text=True)
    msg = p.stderr.strip().splitlines()[-1] if p.stderr.strip() else ""
    return p.returncode, msg


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--scenario", required=True)
    ap.add_argument("--image", required=True)
    a = ap.parse_args()
    ok = True
    for dt in ("0", "1e-7"):
        rc, msg = run(a.mcsim, a.scenario, a.image, dt)
        good = rc == 2 and "did not boot" in msg and "hw.dead_time_s" in msg
        print(f"{'ok  ' if good else 'FAIL'} dead time {dt} s refused: rc {rc}: {msg}")
        ok &= good
    rc, msg = run(a.mcsim, a.scenario, a.image, "2e-7")
    good = rc == 0
    print(f"{'ok  ' if good else 'FAIL'} dead time 2e-7 s (the floor) accepted: rc {rc}: {msg}")
    ok &= good
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
