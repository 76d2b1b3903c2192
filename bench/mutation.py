"""Mutation testing of the physics, the figures and the master (cosmic-ray): each config in
bench/mutation/ names a module and the tests that must kill its mutants; this prints the score
of each and the surviving mutants to review.

    .venv/bin/pip install cosmic-ray
    .venv/bin/python bench/mutation.py [bench/mutation/master.toml ...]

cosmic-ray changes the module in place, one mutant at a time, and puts it back: run it on a
clean checkout (it refuses a module with uncommitted changes) and edit nothing meanwhile. A slow
job, not part of the test suite: the punch's figure module has about 870 mutants.
"""
from __future__ import annotations

import os
import subprocess
import sys
import tomllib
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def run(config: Path) -> None:
    module = tomllib.loads(config.read_text())["cosmic-ray"]["module-path"]
    dirty = subprocess.run(["git", "status", "--porcelain", module], cwd=REPO, text=True,
                           capture_output=True).stdout.strip()
    if dirty:
        sys.exit(f"mutation: {module} has uncommitted changes; commit them first")
    session = REPO / "results" / "mutation" / f"{config.stem}.sqlite"
    session.parent.mkdir(parents=True, exist_ok=True)
    session.unlink(missing_ok=True)
    bin_dir = Path(sys.executable).parent
    env = {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}"}
    for step in (["init", str(config), str(session)], ["exec", str(config), str(session)]):
        subprocess.run([str(bin_dir / "cosmic-ray"), *step], cwd=REPO, env=env, check=True)
    report = subprocess.run([str(bin_dir / "cr-report"), "--show-pending", str(session)],
                            cwd=REPO, env=env, text=True, capture_output=True).stdout
    print(f"== {config.stem}: {module}")
    print(report)


if __name__ == "__main__":
    configs = [Path(a) for a in sys.argv[1:]] or sorted((REPO / "bench" / "mutation").glob("*.toml"))
    for config in configs:
        run(config)
