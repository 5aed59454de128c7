"""Reading the simulator's trace.csv and preparing angle signals for plotting."""

from __future__ import annotations

import io
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mctools.errors import InputError


class TraceError(InputError):
    """Bad trace input; the CLI turns it into exit status 2."""


@dataclass
class Trace:
    path: Path
    columns: dict[str, np.ndarray]

    def __contains__(self, name: str) -> bool:
        return name in self.columns

    def __getitem__(self, name: str) -> np.ndarray:
        return self.columns[name]

    @property
    def t(self) -> np.ndarray:
        return self.columns["t_s"]

    def __len__(self) -> int:
        return len(self.t)


def load_trace(path) -> Trace:
    """Read a CSV trace with a header line. Lines starting with '#' are comments.

    A ragged last line is dropped with a warning: a simulator stopped mid-run may leave one,
    and the rest of the trace is still worth plotting.
    """
    path = Path(path)
    if not path.exists():
        raise TraceError(f"{path}: no such file")
    if not path.is_file():
        raise TraceError(f"{path}: not a regular file")
    text = path.read_text(encoding="utf-8", errors="replace")
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    if not lines:
        raise TraceError(f"{path}: file is empty (no header line)")
    header = [h.strip() for h in lines[0].split(",")]
    if "t_s" not in header:
        raise TraceError(f"{path}: no 't_s' column in header (found: {', '.join(header[:8])}"
                         f"{', ...' if len(header) > 8 else ''})")
    dup = sorted({h for h in header if header.count(h) > 1})
    if dup:
        raise TraceError(f"{path}: duplicate column(s) in header: {', '.join(dup)}")
    body = lines[1:]
    if body and body[-1].count(",") != len(header) - 1:
        print(f"warning: {path}: dropping incomplete last line", file=sys.stderr)
        body = body[:-1]
    if not body:
        raise TraceError(f"{path}: no data rows after the header")
    try:
        data = np.loadtxt(io.StringIO("\n".join(body)), delimiter=",", ndmin=2, dtype=float)
    except ValueError as exc:
        raise TraceError(f"{path}: cannot parse data: {exc}") from None
    if data.shape[1] != len(header):
        raise TraceError(f"{path}: {data.shape[1]} data columns but {len(header)} header names")
    return Trace(path, {name: data[:, k] for k, name in enumerate(header)})


def wrap_deg(a):
    """Wrap degrees to [-180, 180)."""
    return (np.asarray(a, dtype=float) + 180.0) % 360.0 - 180.0


def break_wraps(t, angle_deg, jump_deg: float = 180.0):
    """Insert NaN between samples where a wrapped angle jumps by more than `jump_deg`.

    Matplotlib then lifts the pen instead of drawing a vertical line across the panel
    at every wrap. Returns new (t, angle) arrays; the NaN sits at the mid time.
    """
    t = np.asarray(t, dtype=float)
    a = np.asarray(angle_deg, dtype=float)
    if a.size < 2:
        return t.copy(), a.copy()
    idx = np.flatnonzero(np.abs(np.diff(a)) > jump_deg) + 1
    if idx.size == 0:
        return t.copy(), a.copy()
    t_mid = 0.5 * (t[idx - 1] + t[idx])
    return np.insert(t, idx, t_mid), np.insert(a, idx, np.nan)
