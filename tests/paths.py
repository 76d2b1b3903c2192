"""Where the tests find the repository and their own data, wherever in tests/ they lie."""
from pathlib import Path

TESTS = Path(__file__).resolve().parent
REPO = TESTS.parent
INDEPENDENT = TESTS / "independent"          # the references that share no code with sewfmu
