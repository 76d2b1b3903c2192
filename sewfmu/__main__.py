"""`python -m sewfmu`: the command line."""
import sys

from sewfmu.cli import main

sys.exit(main())
