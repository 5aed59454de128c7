#!/usr/bin/env bash
# The simulated drive on a CAN bus for mctune (docs/can.md): installs what it needs, builds, then
# runs scenarios/can_drive.toml on a socketcand endpoint, paced to real time, its NVM (the CANopen
# store 0x1010) kept in out/can_drive/drive.nvm across runs. Stop it with Ctrl-C.
# Usage: scripts/can_drive.sh [PORT] (default 29536); extra mcsim options after it.
set -euo pipefail
cd "$(dirname "$0")/.."
port="${1:-29536}"
shift || true
scripts/setup.sh
scripts/build.sh
mkdir -p out/can_drive
echo "can_drive: the drive is node 1 on socketcand:127.0.0.1:${port}/can0; in another terminal: .venv/bin/mctune info"
exec build/host/sim/app/mcsim run scenarios/can_drive.toml --out out/can_drive \
  --can "socketcand:127.0.0.1:${port}" --realtime --nvm out/can_drive/drive.nvm "$@"
