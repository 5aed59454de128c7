#!/usr/bin/env python3
"""The simulated drive on CAN (mcsim run --can socketcand:HOST:PORT): python-can's own socketcand
client connects (handshake `< hi >`, `< open can0 >` / `< ok >`, `< rawmode >` / `< ok >`), reads
the device type 0x1000 from the drive's CANopen device by SDO and sees its heartbeat, and the raw protocol is checked for what python-can's
client is strict about: no `< error ... >` in raw mode, commands in any hex case accepted. Uses
python-can when it is importable (the tools' venv), else the raw protocol only."""
import argparse
import socket
import subprocess
import sys
import time
import os
import tempfile


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    p = s.getsockname()[1]
    s.close()
    return p


def connect(port, deadline):
    while time.time() < deadline:
        try:
            return socket.create_connection(("127.0.0.1", port), timeout=2)
        except OSError:
            time.sleep(0.05)
    raise SystemExit("check_socketcand: mcsim never listened")


def read_token(s):
    buf = b""
    while not buf.endswith(b">"):
        c = s.recv(1)
        if not c:
            raise SystemExit("check_socketcand: connection closed")
        buf += c
    return buf.decode().strip()


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--mcsim", required=True)
    ap.add_argument("--scenario", required=True)
    a = ap.parse_args()
    bad = []
    port = free_port()
    p = subprocess.Popen([a.mcsim, "run", a.scenario, "--quiet", "--out", os.path.join(tempfile.gettempdir(), "check_socketcand"),
                          "--set", "scenario.duration_s=3.0", "--set", "output.trace=false",
                          "--can", f"socketcand:127.0.0.1:{port}", "--realtime"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        # 1. the raw protocol
        s = connect(port, time.time() + 10)
        hi = read_token(s)
        if hi != "< hi >":
            bad.append(f"greeting {hi!r}")
        s.sendall(b"< open can0 >")
        if (t := read_token(s)) != "< ok >":
            bad.append(f"open: {t!r}")
        s.sendall(b"< rawmode >")
        if (t := read_token(s)) != "< ok >":
            bad.append(f"rawmode: {t!r}")
        s.sendall(b"< send 60a 8 40 00 10 00 00 00 00 00 >< send 1FFFFFF0 2 aB Cd >< bogus >")
        s.settimeout(0.3)
        try:
            extra = s.recv(4096).decode()
        except socket.timeout:
            extra = ""
        if "error" in extra:
            bad.append(f"answered {extra!r} in raw mode")
        s.close()
        # 2. python-can's client (a new connection after the first closed)
        try:
            import can  # noqa: PLC0415
        except ImportError:
            print("check_socketcand: python-can not importable: raw protocol only")
        else:
            time.sleep(0.2)
            with can.Bus(interface="socketcand", host="127.0.0.1", port=port, channel="can0") as bus:
                bus.send(can.Message(arbitration_id=0x12345, data=[1, 2], is_extended_id=True))
                # the drive's CANopen device (node 1): SDO upload of 0x1000, and its heartbeat
                bus.send(can.Message(arbitration_id=0x601, data=[0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0], is_extended_id=False))
                sdo, heartbeat = None, None
                deadline = time.time() + 4.0
                while time.time() < deadline and (sdo is None or heartbeat is None):
                    m = bus.recv(timeout=0.5)
                    if m is None:
                        continue
                    if m.arbitration_id == 0x581 and sdo is None:
                        sdo = bytes(m.data)
                    if m.arbitration_id == 0x701:
                        heartbeat = bytes(m.data)
                if sdo is None or sdo[0] != 0x43 or int.from_bytes(sdo[4:8], "little") != 0x00020192:
                    bad.append(f"SDO upload of 0x1000 (device type): {sdo!r}")
                if heartbeat is None or heartbeat[0] not in (0x7F, 0x05, 0x04):
                    bad.append(f"heartbeat 0x701: {heartbeat!r}")
            print(f"check_socketcand: python-can {can.__version__}: SDO 0x1000 = "
                  f"{int.from_bytes(sdo[4:8], 'little') if sdo else None:#x}, heartbeat state {heartbeat!r}")
    finally:
        p.terminate()
        p.wait(timeout=10)
    print(f"check_socketcand: raw protocol on port {port}: greeting, open, rawmode acknowledged")
    for b in bad:
        print("check_socketcand: FAIL: " + b)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
