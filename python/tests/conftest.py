"""Shared fixtures of the Python package's tests: the repository's files and the drape binary."""
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
HEMISPHERE = REPO / "geometries" / "hemisphere" / "hemisphere-2k.obj"
GLASS = REPO / "materials" / "glass-plain-weave.toml"


def drape_binary() -> Path:
    """The command line to compare with: $DRAPE_BIN, else the release build of this checkout."""
    if os.environ.get("DRAPE_BIN"):
        return Path(os.environ["DRAPE_BIN"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    return target / "release" / "drape"


@pytest.fixture(scope="session")
def cli():
    """Run the drape command line; returns the finished process (stdout, stderr, returncode)."""
    binary = drape_binary()
    if not binary.exists():
        pytest.fail(f"{binary} is missing: run `cargo build --release` (or set DRAPE_BIN) first")

    def run(*args, check=True):
        done = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        if check and done.returncode != 0:
            raise AssertionError(f"drape {' '.join(map(str, args))} failed: {done.stderr}")
        return done

    return run
