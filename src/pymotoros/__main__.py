"""``python -m pymotoros``."""

from pymotoros.cli.main import main

main()
