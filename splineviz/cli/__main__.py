"""``python -m splineviz.cli``: the ``splineviz`` command (:func:`splineviz.cli.main`)."""

import sys

from splineviz.cli import main

sys.exit(main())
