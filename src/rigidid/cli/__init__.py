"""The ``rigidid`` command line: parse, call one API function, print. Errors become one line on stderr.

Exit status: 0 success, 1 the data determine no rigid body (or ``plan`` finds the
layout unusable), 2 bad input or usage. One module per command; :mod:`rigidid.cli.options`
holds the option types they share and :mod:`rigidid.cli.common` the helpers.
"""

import os

# Before numpy loads: rigidid's matrices are small, and a second BLAS thread made small
# eigenproblems 10-50x slower on a busy 2-core machine (set the variable to override).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
# pydantic would scan every installed package's entry points for plugins at the first
# model it builds; the command line uses none.
os.environ.setdefault("PYDANTIC_DISABLE_PLUGINS", "__all__")

from rigidid.cli.app import app, main, run

__all__ = ["app", "main", "run"]
