"""Moved to :mod:`splineviz.compute.raycast.to_tables` (the truncated-octahedral kernel family);
this import path names the same module."""

import sys

from splineviz.compute.raycast import to_tables

sys.modules[__name__] = to_tables
