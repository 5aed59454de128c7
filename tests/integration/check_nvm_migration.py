"""A stored set survives a firmware update: the NVM image main at 5265cfe saved over CANopen
(tests/integration/data/nvm_main_5265cfe.bin, its old positional format) boots on this build's
mcsim with every value the user stored, read back over CANopen, and 0x2FF1 says the stored set
is in force (0: every value kept). Runs on a copy: the fixture is never rewritten.
Usage: check_nvm_migration.py --mcsim PATH (the tools' venv: python-can, canopen)."""
import argparse
import hashlib
import math
import shutil
import sys
import tempfile
from pathlib import Path

import canopen

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE / "data"))
import make_nvm_main as m  # noqa: E402  (the drive's start/stop and the stored values)

FIXTURE = HERE / "data" / "nvm_main_5265cfe.bin"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mcsim", required=True)
    a = ap.parse_args()
    digest = hashlib.sha256(FIXTURE.read_bytes()).hexdigest()
    bad = []
    with tempfile.TemporaryDirectory() as tmp:
        nvm = Path(tmp) / "drive.nvm"
        shutil.copyfile(FIXTURE, nvm)
        proc, port = m.start(a.mcsim, nvm, Path(tmp) / "run")
        try:
            net = canopen.Network()
            net.connect(interface="socketcand", host="127.0.0.1", port=port, channel="can0")
            node = canopen.RemoteNode(m.NODE, str(m.EDS))
            net.add_node(node)
            node.sdo.RESPONSE_TIMEOUT = 1.0
            try:
                src = node.sdo[0x2FF1].raw
                print(f"configuration source 0x2FF1 = {src}")
                if src != 0:
                    bad.append(f"0x2FF1 = {src}, expected 0 (the stored set, every value kept)")
                for name, want in m.VALUES.items():
                    got = node.sdo[name].raw
                    print(f"{name} = {got} (stored {want})")
                    if not math.isclose(float(got), float(want), rel_tol=0, abs_tol=0):
                        bad.append(f"{name} = {got}, stored {want}")
            finally:
                net.disconnect()
        finally:
            m.stop(proc)
    if hashlib.sha256(FIXTURE.read_bytes()).hexdigest() != digest:
        bad.append(f"{FIXTURE} changed")
    for b in bad:
        print("FAIL:", b)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
