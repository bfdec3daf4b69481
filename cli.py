#!/usr/bin/env python3
"""Run nbst from a checkout: ``python cli.py COMMAND ...`` (the same as ``nbst COMMAND ...``)."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from nbst.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
