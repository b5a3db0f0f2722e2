"""``python -m softtip.cli``: the ``softtip`` command."""

from softtip.cli.app import main

if __name__ == "__main__":  # pragma: no cover
    main()
