"""Counts the cases the fuzz and fault suite tried and prints one summary line."""

import collections

import pytest

#: suite part -> number of cases tried (inputs read, writes failed, faults injected)
TRIED: collections.Counter = collections.Counter()


@pytest.fixture
def tried():
    """``tried[part] += n`` records cases for the summary line."""
    return TRIED


def pytest_terminal_summary(terminalreporter):
    if TRIED:
        parts = ", ".join(f"{k} {v}" for k, v in sorted(TRIED.items()))
        terminalreporter.write_line(f"fuzz/fault suite: {sum(TRIED.values())} cases tried "
                                    f"({parts})")
