"""mctune: tune and drive the IPMSM drive over CANopen from a PC (the `mctune` command).

  errors   MctuneError and its exit statuses: InputError (2), CommError (1)
  bus      the bus given as text (any python-can interface), the canopen Network, heartbeats, NMT
  eds      the EDS with the firmware's extra keys (Unit, Description, Choices, Access); values
           parsed and range-checked against an entry
  drive    Drive (a canopen RemoteNode): SDO, NMT, CiA 402, store / restore, the scope; SDO aborts,
           states and values in words
  faults   the drive's fault bits and EMCYs by name (data/faults.json, from mc/faults.h)
  capture  TPDO recordings (monitor) and scope records as CSV and PNG
  cli      the command line (`mctune`, `python -m mctools.mctune`)
"""

from mctools.mctune.cli import build_parser, main
from mctools.mctune.drive import Drive
from mctools.mctune.eds import Eds, fmt_num
from mctools.mctune.errors import CommError, InputError

__all__ = ["main", "build_parser", "Drive", "Eds", "CommError", "InputError", "fmt_num"]
