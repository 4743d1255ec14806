"""``python -m rigidid``."""

from rigidid.cli import main

main()
