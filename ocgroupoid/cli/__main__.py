"""``python -m ocgroupoid.cli``: the command line, as ``python -m ocgroupoid``."""

from . import main

main()
