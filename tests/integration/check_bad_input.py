#!/usr/bin/env python3
"""Malformed scenarios must be rejected before anything runs: exit status 2 and a message that
names the offending key (or the file). Each case: (args, text that must appear in stderr, or a
tuple of such texts). Every message stays below MAX_STDERR bytes (a 1 MB key is not echoed)."""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
GOOD = os.path.join(HERE, "..", "..", "scenarios", "speed_step_inertia.toml")
MAX_STDERR = 2048


def cases(tmp):
    bad = lambda name: os.path.join(HERE, "bad", name)
    huge_key = os.path.join(tmp, "huge_key.toml")  # 1 MB unknown key (generated: not in the repo)
    with open(huge_key, "w") as f:
        f.write("[scenario]\n" + "k" * 1_000_000 + " = 1\n")
    huge_file = os.path.join(tmp, "huge_file.toml")  # valid TOML, but beyond the 1 MiB limit
    with open(huge_file, "w") as f:
        f.write("[scenario]\n" + "#" * (1 << 20) + "\n")
    short_nvm = os.path.join(tmp, "short.nvm")  # not an NVM image of this drive
    with open(short_nvm, "wb") as f:
        f.write(b"0123456789")
    raw_nul = os.path.join(tmp, "raw_nul.toml")  # a literal NUL byte inside a string
    with open(raw_nul, "wb") as f:
        f.write(b'[scenario]\nname = "a\x00b"\n')
    return [
        # presets: every number checked (finite, plausible range), the message names key and range
        (["run", GOOD, "--set", 'machine.preset="%s"' % bad("preset_ld_1e300.toml")],
         ("machine.preset", "ld_h", "1e+300", "out of range", "<= 10 H")),
        # NUL in a string: shown escaped, and the message goes on past it
        (["run", bad("nul_in_string.toml")], ("scenario.duration_s", '"x\\x00y"', "wrong type")),
        (["check", raw_nul], "raw_nul.toml"),
        (["check", GOOD, "--set", "scenario.duration_s=\"a\x01b\""], ("scenario.duration_s", "a\\x01b")),
        # a 1 MB key is cut (the length check below), the file is bounded, devices are refused
        (["check", huge_key], ("unknown key", "(1000009 bytes)")),
        (["check", huge_file], ("huge_file.toml", "larger than")),
        (["check", "/dev/zero"], ("/dev/zero", "not a regular file")),
        (["check", tmp], "is a directory"),
        (["check", GOOD, "--set", "x" * 100_000 + ".y=1"], "unknown key"),
        (["run", GOOD, "--set", "inverter.integrator=\"rippel\""], ("inverter.integrator", "taylor|hermite|rk4")),
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
        # the drive's NVM file (the CANopen store): another size is refused, not guessed at
        (["run", GOOD, "--nvm", short_nvm], ("--nvm", "10 bytes, expected 16384")),
        (["run", GOOD, "--set", "can.commands=\"bus\""], ("can.commands", "canopen|scenario")),
        (["run", GOOD, "--can", "socketcand:127.0.0.1:99999"], ("--can", "1..65535")),
    ]


def main():
    mcsim = sys.argv[1]
    failed = 0
    with tempfile.TemporaryDirectory() as out, tempfile.TemporaryDirectory() as tmp:
        for args, needle in cases(tmp):
            extra = ["--out", out, "--quiet"] if args[0] == "run" else []
            r = subprocess.run([mcsim] + args + extra, capture_output=True, timeout=60)
            err = r.stderr.decode("utf-8", "replace")
            ran = os.path.exists(os.path.join(out, "metrics.json"))
            needles = needle if isinstance(needle, tuple) else (needle,)
            missing = [n for n in needles if n not in err]
            ok = r.returncode == 2 and not missing and not ran and len(r.stderr) <= MAX_STDERR
            shown = " ".join(a if len(a) < 100 else a[:40] + f"...({len(a)} chars)" for a in args)
            why = f" (missing {missing})" if missing else ""
            why += f" ({len(r.stderr)} bytes of stderr)" if len(r.stderr) > MAX_STDERR else ""
            print(f"{'ok  ' if ok else 'FAIL'}: {shown} -> exit {r.returncode}{why}: {err.strip()[:400]}")
            failed += 0 if ok else 1
    # a removed choice keeps a scenario running, with one deprecation line
    r = subprocess.run([mcsim, "check", GOOD, "--set", "inverter.integrator=\"ripple\""], capture_output=True, text=True)
    ok = r.returncode == 0 and "deprecated" in r.stderr and r.stderr.count("\n") == 1 and "taylor" in r.stderr
    print(f"{'ok  ' if ok else 'FAIL'}: integrator \"ripple\" -> exit {r.returncode} {r.stderr.strip()}")
    failed += 0 if ok else 1
    # and the good file with a valid --set passes validation
    r = subprocess.run([mcsim, "check", GOOD, "--set", "control.current_bw_hz=400"], capture_output=True, text=True)
    ok = r.returncode == 0
    print(f"{'ok  ' if ok else 'FAIL'}: check with a valid --set -> exit {r.returncode} {r.stderr.strip()}")
    failed += 0 if ok else 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
