"""How a `mctools` subcommand refuses its input (arguments, files, scenarios, presets): it raises
an `InputError` (each module derives its own, e.g. TraceError, PresetError, SweepInputError), and
`mctools` prints `mctools COMMAND: error: MESSAGE` on stderr and exits with EXIT_BAD_INPUT."""

EXIT_BAD_INPUT = 2


class InputError(Exception):
    """Input a subcommand refuses; the CLI turns it into exit status EXIT_BAD_INPUT."""
