"""`python -m sewfmu`: the command line."""
import sys

from .scenarios.cli import main

sys.exit(main())
