"""``python -m nbst.cli``: the same as the ``nbst`` command."""
import sys

from nbst.cli.main import main

sys.exit(main())
