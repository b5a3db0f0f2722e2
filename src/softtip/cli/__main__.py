"""``python -m softtip.cli``: the ``softtip`` command."""

from softtip.cli.app import _one_blas_thread, main

if __name__ == "__main__":  # pragma: no cover
    _one_blas_thread()
    main()
