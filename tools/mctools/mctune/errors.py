"""Errors of `mctune`, each with the exit status the command line gives it: `InputError` (2) for
input the tool or the drive refuses, `CommError` (1) for a bus or a drive that does not answer."""

from __future__ import annotations

EXIT_COMM = 1
EXIT_INPUT = 2


class MctuneError(Exception):
    exit_code = EXIT_COMM


class InputError(MctuneError):
    """Input the tool refuses, or the drive refused (SDO abort): exit status 2."""
    exit_code = EXIT_INPUT


class CommError(MctuneError):
    """The bus cannot be opened, the drive does not answer or does not reach a state: 1."""
    exit_code = EXIT_COMM
