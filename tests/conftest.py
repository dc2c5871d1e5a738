import os
import sys
from pathlib import Path

import pytest

TESTS = Path(__file__).parent
sys.path.insert(0, str(TESTS))  # test helpers (thesis_tables.py) import as top-level modules

#: the real data sets, next to the repository (never copied into it);
#: $SPLINEVIZ_SHARED_DATA names them for checkouts elsewhere (git worktrees)
SHARED_DATA = Path(os.environ.get("SPLINEVIZ_SHARED_DATA")
                   or TESTS.parent.parent / "shared" / "data")


@pytest.fixture(scope="session")
def shared_data():
    if not SHARED_DATA.is_dir():
        pytest.skip(f"shared data folder {SHARED_DATA} not found")
    return SHARED_DATA
