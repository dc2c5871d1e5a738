"""Moved to :mod:`splineviz.compute.raycast.to_program` (the truncated-octahedral kernel family);
this import path names the same module."""

import sys

from splineviz.compute.raycast import to_program

sys.modules[__name__] = to_program
