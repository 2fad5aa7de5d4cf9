"""Shared fixtures: the repository's folders and the `fspec` command line."""

import os
import pathlib
import subprocess

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def repo() -> pathlib.Path:
    """The repository root (scenes, data)."""
    return REPO


@pytest.fixture(scope="session")
def fspec_cli() -> pathlib.Path:
    """The release `fspec` binary the renders are compared with.

    `FSPEC_CLI` names it (`.ci/run` sets it after `cargo build --release -p
    cli`; a missing file then fails the tests). Without the variable the
    tests use `target/release/fspec` and are skipped where it was not built.
    """
    named = os.environ.get("FSPEC_CLI")
    path = pathlib.Path(named) if named else REPO / "target" / "release" / "fspec"
    if not path.is_file():
        if named:
            pytest.fail(f"FSPEC_CLI={named} does not exist")
        pytest.skip("target/release/fspec not built (cargo build --release -p cli) and FSPEC_CLI not set")
    return path


def run_cli(binary: pathlib.Path, *arguments: str) -> subprocess.CompletedProcess:
    """Runs `fspec` with `arguments`, capturing its output as text."""
    return subprocess.run([str(binary), *arguments], capture_output=True, text=True, timeout=600)
