"""``python -m retarget``: the CLI, for launchers that start a module (``torchrun -m retarget
train RECIPE``)."""

import sys

from retarget.cli.main import main

sys.exit(main())
