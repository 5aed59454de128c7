import sys

from mctools.cli import main

sys.exit(main())
