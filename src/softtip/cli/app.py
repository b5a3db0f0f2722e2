"""The ``softtip`` command group: error handling common to every command, and the commands."""

from __future__ import annotations

import os
import signal
import sys

import click

from softtip import __version__
from softtip.cli.calibrate import calibrate
from softtip.cli.calibrate_payload import calibrate_payload
from softtip.cli.estimate import estimate
from softtip.cli.fuse import fuse
from softtip.cli.options import FRAMES_HELP
from softtip.cli.reproduce import reproduce
from softtip.cli.simulate import simulate
from softtip.cli.stream import stream
from softtip.errors import InputError

__all__ = ["main"]


def _import_pandas_if_installed() -> None:
    """pyarrow imports pandas lazily, the first time it converts a table, when pandas is
    installed (it is not a dependency of softtip). A signal whose handler raises inside that
    long import can leave the interpreter's import lock held, and the run then hangs at its
    next import instead of ending. So the import happens here, before softtip's signal
    handlers are armed (a signal now ends the process the default way); without pandas this
    costs one look-up. The console command (:func:`run`) never imports pandas instead
    (:class:`_WithoutPandas`)."""
    import importlib.util

    if not any(isinstance(finder, _WithoutPandas) for finder in sys.meta_path) and importlib.util.find_spec("pandas"):
        import pandas  # noqa: F401


class _WithoutPandas:
    """A module finder that refuses pandas, for the console command's process: every command
    runs as where pandas is not installed (it is not a dependency of softtip, and no command
    uses it). pyarrow would otherwise import it the first time it converts a column, about
    0.35 s of CPU, half the start-up of a short run, and an import that a signal could
    interrupt (:func:`_import_pandas_if_installed`). Refusing it here rather than hiding it
    from ``sys.modules``: pyarrow's compiled import takes a ``None`` there for the module."""

    def find_spec(self, name: str, path=None, target=None):
        if name == "pandas" or name.startswith("pandas."):
            raise ImportError("the softtip command runs without pandas", name=name)
        return None


class _Group(click.Group):
    def invoke(self, ctx):
        from softtip.io.atomic import cannot_write, silence_stdout
        from softtip.io.interrupt import Interrupted, exit_code, exit_now, interrupted_signal, terminate_like_ctrl_c

        _import_pandas_if_installed()  # a command runs (the group's --help and --version end before)
        try:
            with terminate_like_ctrl_c():
                result = super().invoke(ctx)
                try:
                    sys.stdout.flush()  # a full device or a closed pipe shows here at the latest
                except OSError as exc:
                    silence_stdout()
                    raise cannot_write("standard output", exc) from None
                return result
        except InputError as exc:
            click.echo(f"softtip: error: {exc}", err=True)
            ctx.exit(2)
        except MemoryError:
            click.echo(
                "softtip: error: out of memory; for a large log give --chunk-rows N (pieces of N rows: memory "
                "bounded by N), or free memory (no output file was written)",
                err=True,
            )
            ctx.exit(1)
        except OSError as exc:  # the last line of defence: an OS failure no command worded itself
            where = f"{exc.filename}: " if getattr(exc, "filename", None) else ""
            click.echo(f"softtip: error: {where}{exc.strerror or exc} (check the path and its permissions)", err=True)
            ctx.exit(2)
        except KeyboardInterrupt as exc:
            # Ctrl-C, SIGTERM, SIGHUP: every temporary file is gone by now (unwound like an error)
            name = exc.signal_name if isinstance(exc, Interrupted) else "SIGINT"
            click.echo(f"softtip: interrupted ({name})", err=True)
            exit_now(exit_code(exc))  # by a real signal: now, whatever follows it
            ctx.exit(exit_code(exc))
        except Exception:
            sig = interrupted_signal()
            if sig is None:
                raise
            # a signal a library swallowed (an interrupted import, say) surfaced as another error:
            # the outputs were discarded on the way; end as the signal
            click.echo(f"softtip: interrupted ({signal.Signals(sig).name})", err=True)
            exit_now(128 + sig)
            ctx.exit(128 + sig)


@click.group(cls=_Group, help="softtip: intrinsic tactile sensing with a soft fingertip on a six-axis F/T sensor.\n\n" + FRAMES_HELP)
@click.version_option(__version__, prog_name="softtip")
def main() -> None:
    pass



for _command in (estimate, stream, simulate, reproduce, calibrate, calibrate_payload, fuse):
    main.add_command(_command)


def run() -> None:
    """The ``softtip`` console command: :data:`main`; a run that failed then ends at once.

    After a failure every output has been discarded and the message written, so nothing is
    left for the interpreter's finalisation to do but destroy native libraries' state; there a
    reader thread of a native library that is still winding down occasionally aborts the
    process (``terminate called without an active exception``, exit -6 instead of the
    failure's code). So a failed run flushes its streams and exits with its code directly; a
    successful one ends normally. In-process callers (tests) use :data:`main` itself.
    """
    from softtip.io.interrupt import ignore_signals_after_commit_until_exit

    ignore_signals_after_commit_until_exit()
    if "pandas" not in sys.modules:
        sys.meta_path.insert(0, _WithoutPandas())
    try:
        main(standalone_mode=True)
    except SystemExit as exc:
        code = exc.code
        if code in (0, None):
            raise
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:  # noqa: BLE001 - a closed pipe: nothing more can be said
                pass
        os._exit(code if isinstance(code, int) else 1)
