"""The ``softtip`` command group: error handling common to every command, and the commands."""

from __future__ import annotations

import importlib
import os
import signal
import sys
from collections.abc import Iterator, Mapping

import click

from softtip import __version__
from softtip.cli.frames import FRAMES_HELP
from softtip.errors import InputError

__all__ = ["main"]

#: The commands: name -> (module, the command in it, the first paragraph of its help, which
#: ``softtip --help`` lists). A command's module is imported only when the command runs or its
#: help is shown: importing all of them took most of the start-up of every run.
COMMANDS: dict[str, tuple[str, str, str]] = {
    "calibrate": ("softtip.cli.calibrate", "calibrate",
                  "Calibrate the fingertip geometry from a probing log of plane presses."),
    "calibrate-payload": ("softtip.cli.calibrate_payload", "calibrate_payload",
                          "Estimate the fingertip's mass, centre of mass and the sensor bias."),
    "estimate": ("softtip.cli.estimate", "estimate",
                 "Estimate contact point, normal, spin torque, contact state and edge direction from a force/torque log."),
    "fuse": ("softtip.cli.fuse", "fuse",
             "Fuse two fingertips into the grasped object's local geometry, in a common frame."),
    "reproduce": ("softtip.cli.reproduce", "reproduce",
                  "Reproduce the papers' experiments (manual §5, E1–E6) on the simulator."),
    "simulate": ("softtip.cli.simulate", "simulate",
                 "Simulate a grasp of an object by the soft fingertip and write the F/T log."),
    "stream": ("softtip.cli.stream", "stream",
               "Estimate live: from an ATI Net F/T or Axia sensor, or a replayed log."),
}  # fmt: skip


class _Commands(Mapping):
    """The group's commands by name (click's ``Group.commands``), from :data:`COMMANDS`: a
    command's module is imported the first time the command is looked up."""

    def __init__(self) -> None:
        self._loaded: dict[str, click.Command] = {}

    def __getitem__(self, name: str) -> click.Command:
        if name not in self._loaded:
            module, attribute, _ = COMMANDS[name]  # KeyError: no such command
            self._loaded[name] = getattr(importlib.import_module(module), attribute)
        return self._loaded[name]

    def __iter__(self) -> Iterator[str]:
        return iter(COMMANDS)

    def __len__(self) -> int:
        return len(COMMANDS)


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
    def format_commands(self, ctx, formatter):
        # the list from the registry's one-line help, without importing every command's module
        listed = click.Group(commands=[click.Command(name, help=help) for name, (_, _, help) in COMMANDS.items()])
        click.Group.format_commands(listed, ctx, formatter)

    def invoke(self, ctx):
        from softtip.io.atomic import cannot_write, silence_stdout
        from softtip.io.interrupt import Interrupted, exit_code, exit_now, interrupted_signal, terminate_like_ctrl_c

        # the command's module is imported now, before the signal handlers are armed, for the
        # reason pandas is (click keeps the command's name there until Group.invoke)
        name = next(iter(getattr(ctx, "_protected_args", ())), None)
        if name is not None:
            self.get_command(ctx, name)
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


main.commands = _Commands()


def _one_blas_thread(environ: dict[str, str] | None = None) -> None:
    """Run OpenBLAS (numpy's and scipy's linear algebra) on one thread in this process and the
    processes it starts, unless ``OPENBLAS_NUM_THREADS`` or ``OMP_NUM_THREADS`` says otherwise.

    softtip's maths works on 3-vectors and small matrices, sample by sample, where a BLAS thread
    pool only costs: starting one per library took 0.1 s of CPU of every command (0.3 s with the
    compiled steps, whose numba loads scipy's own OpenBLAS), half the CPU of a short run, and
    its threads compete with ``--jobs``. Effective only before numpy is first imported, hence
    at the command's entry."""
    environ = os.environ if environ is None else environ
    if "OPENBLAS_NUM_THREADS" not in environ and "OMP_NUM_THREADS" not in environ:
        environ["OPENBLAS_NUM_THREADS"] = "1"


def run() -> None:
    """The ``softtip`` console command: :data:`main`; a run that failed then ends at once.

    After a failure every output has been discarded and the message written, so nothing is
    left for the interpreter's finalisation to do but destroy native libraries' state; there a
    reader thread of a native library that is still winding down occasionally aborts the
    process (``terminate called without an active exception``, exit -6 instead of the
    failure's code). So a failed run flushes its streams and exits with its code directly; a
    successful one ends normally, but for the cyclic garbage collection of the objects left
    (:func:`_leave_objects_to_the_exit`). In-process callers (tests) use :data:`main` itself.
    """
    _one_blas_thread()  # before anything imports numpy
    from softtip.io.interrupt import ignore_signals_after_commit_until_exit

    ignore_signals_after_commit_until_exit()
    if "pandas" not in sys.modules:
        sys.meta_path.insert(0, _WithoutPandas())
    try:
        main(standalone_mode=True)
    except SystemExit as exc:
        code = exc.code
        if code in (0, None):
            _leave_objects_to_the_exit()
            raise
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except Exception:  # noqa: BLE001 - a closed pipe: nothing more can be said
                pass
        os._exit(code if isinstance(code, int) else 1)


def _leave_objects_to_the_exit() -> None:
    """Take every object left out of the cyclic garbage collector (:func:`gc.freeze`): the
    collections of the interpreter's finalisation then pass them by.

    Those collections went over every object left, most of them numba's and llvmlite's, and
    took 0.16 s of the 0.75 s of CPU time of a 20,000-row `softtip estimate` with its compiled
    kernels (whole process, median of fifteen runs each). A successful run has committed and
    closed its outputs by then; exit handlers still run and the standard streams are still
    flushed; objects in reference cycles are left to the process's exit instead of being taken
    apart one by one.
    """
    import gc

    gc.freeze()
