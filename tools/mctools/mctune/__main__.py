import sys

from mctools.mctune.cli import main

sys.exit(main())
