"""``python -m c1surf``: the command line, as the ``c1surf`` console script runs it (the same group, the same
program name in its usage and error lines)."""
from .cli.main import main

if __name__ == "__main__":  # pragma: no cover - run as a module
    main(prog_name="c1surf")
