"""``python -m ocgroupoid``: the command line."""

from .cli import main

main()
