"""Write an NVM image the way a user does: the simulated drive (`mcsim run scenarios/can_drive.toml
--can socketcand:... --nvm FILE`), a few parameters changed over SDO, then the CANopen store 0x1010.

Made nvm_main_5265cfe.bin with the firmware and mcsim of main at 5265cfe (the last store format
keyed by the whole table's hash, positional values); tests/integration/check_nvm_migration.py
boots a copy of it on the current build and reads the values back (README.md here).
Usage: make_nvm_main.py --mcsim build/host/sim/app/mcsim --out FILE
Needs the tools' venv (python-can, canopen); the endpoint listens on loopback only."""
import argparse
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import canopen

ROOT = Path(__file__).resolve().parents[3]
EDS = ROOT / "tools" / "mctools" / "data" / "drive.eds"
SCENARIO = ROOT / "scenarios" / "can_drive.toml"
NODE = 1

# What the user changes before the store: one of each type and access (name: value). The
# integration test expects exactly these back.
VALUES = {
    "control.current_bw_hz": 80.0,          # F32, RUNTIME
    "estimator.k1": 0.75,                   # F32, STANDSTILL (the estimator)
    "estimator.iter_max": 6,                # I32, STANDSTILL
    "control.decouple": 0,                  # BOOL
    "protection.lock_action": 1,            # ENUM: recover
    "startup.step1_cost": 2,                # ENUM: fluxdiff
}


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


def start(mcsim, nvm, out):
    port = free_port()
    proc = subprocess.Popen(
        [mcsim, "run", str(SCENARIO), "--quiet", "--out", str(out), "--set", "scenario.duration_s=120",
         "--can", f"socketcand:127.0.0.1:{port}", "--realtime", "--nvm", str(nvm)],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.time() + 20
    while time.time() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"mcsim exited: {proc.stderr.read()}")
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return proc, port
        except OSError:
            time.sleep(0.05)
    proc.kill()
    raise RuntimeError("mcsim never listened")


def stop(proc):
    proc.terminate()
    try:
        proc.wait(timeout=10)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--out", required=True, type=Path)
    a = ap.parse_args()
    a.out.unlink(missing_ok=True)
    with tempfile.TemporaryDirectory() as tmp:
        proc, port = start(a.mcsim, a.out, Path(tmp) / "run")
        try:
            net = canopen.Network()
            net.connect(interface="socketcand", host="127.0.0.1", port=port, channel="can0")
            node = canopen.RemoteNode(NODE, str(EDS))
            net.add_node(node)
            node.sdo.RESPONSE_TIMEOUT = 1.0
            try:
                print(f"table hash 0x2FF0 = {node.sdo[0x2FF0].raw:#010x}")
                for name, v in VALUES.items():
                    before = node.sdo[name].raw
                    node.sdo[name].raw = v
                    print(f"{name}: {before} -> {node.sdo[name].raw}")
                node.sdo[0x1010][1].raw = 0x65766173          # "save"
                st = node.sdo[0x2FF2].raw
                print(f"store status 0x2FF2 = {st}")
                if st not in (0, 7):
                    sys.exit(f"the store failed: {st}")
            finally:
                net.disconnect()
            time.sleep(0.5)                                   # mcsim writes the file after the store
        finally:
            stop(proc)
    print(f"{a.out}: {a.out.stat().st_size} bytes")


if __name__ == "__main__":
    main()
