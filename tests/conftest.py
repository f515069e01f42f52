import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))


@pytest.fixture
def no_records(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """No region recorded by earlier runs (of this test, in the user's cache) for the programs a
    test translates: its regions are found and written in the process (the programs' manifests in
    an empty folder, robosoc.jit.manifest; the objects stay where the process's compiler keeps them)."""
    monkeypatch.setenv("ROBOSOC_CACHE", str(tmp_path))
