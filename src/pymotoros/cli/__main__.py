"""``python -m pymotoros.cli``."""

from pymotoros.cli.main import main

main()
