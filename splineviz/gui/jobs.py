"""Long work off the GUI thread, with progress, a cancel that acts at once, and one message
per error.

Work that is mostly Python (the remesher's advancing front) runs in a child process
(``process=True``): a thread would hold the GIL for hundreds of milliseconds at a time and
stall the window, and a process can be stopped on Cancel. The child reports progress
through a queue; its result and errors come back pickled.

:class:`JobRunner` runs a function in a daemon thread. The function may take a keyword
``job`` (a :class:`JobContext`): ``job.progress(fraction, message)`` reports progress and
returns False once the user cancelled, and ``job.cancelled`` can be polled; functions that
cannot check (reading a file) simply run on. Either way a cancel *acts* within
:data:`CANCEL_GRACE_S`: the status shows "cancelling ...", the job gets that long to stop by
itself, then it is detached — the window is idle again and its result, should it still
arrive, is dropped. Results and errors reach the GUI thread through queued Qt signals.
"""

from __future__ import annotations

import inspect
import multiprocessing
import os
import pickle
import queue
import threading
import time

from PySide6.QtCore import QObject, QTimer, Signal, Slot

from splineviz.core.errors import SplinevizError

#: seconds a cancelled job may take to stop by itself before it is detached
CANCEL_GRACE_S = 0.5


class Cancelled(SplinevizError):
    """Raised inside a job that noticed it was cancelled."""


class JobContext:
    """What a running job sees: progress reporting and the cancel flag (thread safe)."""

    def __init__(self, job: Job):
        self._job = job

    @property
    def cancelled(self) -> bool:
        return self._job._cancel.is_set()

    def progress(self, fraction: float | None, message: str = "") -> bool:
        """Report progress (``fraction`` in [0, 1], None: unknown); False once cancelled."""
        self._job._bridge.progressed.emit(-1.0 if fraction is None else float(fraction),
                                          str(message))
        return not self.cancelled

    def check(self) -> None:
        """Raise :class:`Cancelled` if the user cancelled."""
        if self.cancelled:
            raise Cancelled(f"{self._job.label} cancelled")


class _Bridge(QObject):
    """Carries a job's results from its thread to the GUI thread: the bridge lives in the GUI
    thread, so signals emitted in the job's thread reach its slots queued."""

    progressed = Signal(float, str)
    returned = Signal(object)
    failed = Signal(object)

    def __init__(self, job: Job):
        super().__init__()
        self._job = job
        self.progressed.connect(self._on_progressed)
        self.returned.connect(self._on_returned)
        self.failed.connect(self._on_failed)

    @Slot(float, str)
    def _on_progressed(self, fraction, message):
        self._job._progressed(fraction, message)

    @Slot(object)
    def _on_returned(self, result):
        self._job._returned(result)

    @Slot(object)
    def _on_failed(self, exc):
        self._job._failed(exc)


class Job:
    """One piece of background work (see :class:`JobRunner`)."""

    def __init__(self, runner: JobRunner, label: str, func, args, kwargs, on_done,
                 on_error, cancellable: bool, process: bool = False):
        self.label = label
        self.cancellable = cancellable
        self.state = "running"  # running | cancelling | done | failed | cancelled
        self.fraction: float | None = None
        self.message = ""
        self.started = time.perf_counter()
        self._runner = runner
        #: called with the job when it ended (done, failed or cancelled); None: nobody is
        #: told
        self.on_end = None
        self._on_done = on_done
        self._on_error = on_error
        self._cancel = threading.Event()
        self._bridge = _Bridge(self)
        if process:
            func, args, kwargs = _in_process, (func, args, kwargs, JobContext(self)), {}
        elif "job" in _parameters(func):
            kwargs = {**kwargs, "job": JobContext(self)}
        self._thread = threading.Thread(target=self._run, args=(func, args, kwargs),
                                         name=f"splineviz job: {label}", daemon=True)

    @property
    def active(self) -> bool:
        return self.state in ("running", "cancelling")

    def _run(self, func, args, kwargs) -> None:
        try:
            result = func(*args, **kwargs)
        except BaseException as exc:  # noqa: BLE001  (handed to the GUI thread)
            try:
                self._bridge.failed.emit(exc)
            except RuntimeError:  # the window (and the bridge) is gone
                pass
            return
        try:
            self._bridge.returned.emit(result)
        except RuntimeError:
            pass

    def _progressed(self, fraction: float, message: str) -> None:
        if self.state == "running":
            self.fraction = None if fraction < 0 else min(max(fraction, 0.0), 1.0)
            self.message = message
            self._runner.changed.emit()

    def _returned(self, result) -> None:
        if self.state == "running":
            self._finish("done")
            if self._on_done is not None:
                self._runner._call(self._on_done, result)
        elif self.state == "cancelling":
            self._finish("cancelled")

    def _failed(self, exc) -> None:
        if self.state == "cancelling" or isinstance(exc, Cancelled):
            if self.active:
                self._finish("cancelled")
            return
        if self.state != "running":
            return
        self._finish("failed")
        if self._on_error is not None:
            self._runner._call(self._on_error, exc)
        else:
            self._runner.error.emit(error_message(exc))

    def cancel(self) -> None:
        """Ask the job to stop; detach it after :data:`CANCEL_GRACE_S` if it does not."""
        if self.state != "running":
            return
        self.state = "cancelling"
        self._cancel.set()
        self._runner.changed.emit()
        QTimer.singleShot(int(CANCEL_GRACE_S * 1000), self._detach)

    def _detach(self) -> None:
        if self.state == "cancelling":
            self._finish("cancelled")

    def _finish(self, state: str) -> None:
        self.state = state
        self._runner._finished(self)
        if self.on_end is not None and not self._runner.closed:
            self._runner._call(self.on_end, self)

    def wait(self, timeout_s: float) -> bool:
        """Block until the thread ends (tests, shutdown); True if it did."""
        self._thread.join(timeout_s)
        return not self._thread.is_alive()


#: nice increment of job processes: on a machine with few cores the GUI gets a core first.
#: (Not for job threads: a low-priority thread that holds the GIL would make the GUI thread
#: wait longer — measured: 360 ms stalls instead of 50 ms.)
JOB_NICENESS = 8


def _yield_to_the_gui() -> None:
    try:
        os.nice(JOB_NICENESS)
    except (AttributeError, OSError):  # not allowed: run at normal priority
        pass
    # and every core but one: the job's own threads (the point projection's, the k-d trees')
    # would otherwise take them all (with a remesh on both of 2 cores, the stall test of the
    # GUI thread failed in the full suite despite the nice level)
    try:
        cores = sorted(os.sched_getaffinity(0))
        if len(cores) > 1:
            os.sched_setaffinity(0, cores[1:])
    except (AttributeError, OSError):  # no affinity on this platform
        pass


class _ChildJob:
    """The job context a function sees in a child process: progress goes to the parent."""

    cancelled = False  # the parent stops the process instead

    def __init__(self, messages):
        self._messages = messages

    def progress(self, fraction, message: str = "") -> bool:
        self._messages.put(("progress", (fraction, str(message))))
        return True

    def check(self) -> None:
        pass


def _child_main(func, args, kwargs, messages) -> None:
    _yield_to_the_gui()
    if "job" in _parameters(func):
        kwargs = {**kwargs, "job": _ChildJob(messages)}
    try:
        messages.put(("result", func(*args, **kwargs)))
    except BaseException as exc:  # noqa: BLE001  (handed to the parent)
        try:
            pickle.dumps(exc)
        except Exception:  # noqa: BLE001  (an exception that does not pickle: its text)
            exc = RuntimeError(f"{type(exc).__name__}: {exc}")
        messages.put(("error", exc))


def call_named(target: str, *args, **kwargs):
    """Call the function ``target`` (``"module:function"``) with the arguments, importing its
    module where the call runs: a job process (whose fork server preloads it) can run a
    function whose module the GUI process never imports. The remesher pulls in numba and its
    compiled kernels, 0.7-1.5 s of imports that froze the window at the first Remesh."""
    from importlib import import_module

    module, name = target.split(":")
    return getattr(import_module(module), name)(*args, **kwargs)


def _process_context():
    """Job processes fork from a small server process (started once, by
    :func:`start_process_server`), never from the GUI process: forking a process of ~1 GB
    that runs Qt threads is unsafe, and copying its page tables held the GIL for ~100 ms."""
    try:
        return multiprocessing.get_context("forkserver")
    except ValueError:  # no fork server on this platform
        return multiprocessing.get_context("spawn")


def start_process_server(preload=("splineviz.pointcloud.remesh", "splineviz.model.opening",
                                  "splineviz.io.volumes", "splineviz.io.points")) -> None:
    """Start the fork server now (at start-up, before the window is shown) with the
    modules job processes need already imported."""
    ctx = _process_context()
    if ctx.get_start_method() != "forkserver":
        return
    ctx.set_forkserver_preload(list(preload))
    from multiprocessing import forkserver

    forkserver.ensure_running()


def _in_process(func, args, kwargs, job: JobContext):
    """Run ``func`` in a spawned child process (job thread side): forward its progress,
    stop it on cancel, return its result or raise its error."""
    ctx = _process_context()
    messages = ctx.Queue()
    child = ctx.Process(target=_child_main, args=(func, args, kwargs, messages), daemon=True,
                        name=f"splineviz job: {job._job.label}")
    child.start()
    try:
        while True:
            try:
                kind, payload = messages.get(timeout=0.05)
            except queue.Empty:
                if job.cancelled:
                    raise Cancelled(f"{job._job.label} cancelled") from None
                if not child.is_alive() and messages.empty():
                    raise RuntimeError(f"the worker process of {job._job.label} ended "
                                       f"unexpectedly (exit code {child.exitcode})") from None
                continue
            if kind == "progress":
                job.progress(*payload)
            elif kind == "error":
                raise payload
            else:
                return payload
    finally:
        if child.is_alive():
            child.terminate()
        child.join(2.0)
        messages.close()


def _parameters(func) -> set[str]:
    try:
        return set(inspect.signature(func).parameters)
    except (TypeError, ValueError):
        return set()


def error_message(exc: BaseException) -> str:
    """One sentence for the user: the message of our errors and of OS errors, else the
    exception's type and text (never a traceback)."""
    if isinstance(exc, SplinevizError | OSError | ValueError):
        return str(exc) or type(exc).__name__
    return f"{type(exc).__name__}: {exc}"


class JobRunner(QObject):
    """Runs :class:`Job` objects and tells the window about them.

    Signals
    -------
    changed()
        A job started, progressed, is being cancelled or ended.
    error(str)
        A job without its own error handler failed: one sentence to show.
    """

    changed = Signal()
    error = Signal(str)
    message = Signal(str)

    def __init__(self, parent=None):
        super().__init__(parent)
        self.jobs: list[Job] = []
        self.closed = False
        self._left: list[Job] = []
        #: cancelled jobs detached while their thread still ran (joined on close too)
        self._detached: list[Job] = []

    def run(self, label: str, func, *args, on_done=None, on_error=None,
            cancellable: bool = True, process: bool = False, **kwargs) -> Job:
        """Start ``func(*args, **kwargs)`` in a thread (``job=`` added if it takes one), or
        in a child process (``process=True``: ``func`` and its arguments must pickle);
        ``on_done(result)`` / ``on_error(exc)`` run in the GUI thread."""
        job = Job(self, label, func, args, kwargs, on_done, on_error, cancellable, process)
        self.jobs.append(job)
        job._thread.start()
        self.changed.emit()
        return job

    def _call(self, callback, value) -> None:
        if self.closed:
            return
        try:
            callback(value)
        except Exception as exc:  # noqa: BLE001  (a slot error is a message, not a crash)
            self.error.emit(error_message(exc))

    def _finished(self, job: Job) -> None:
        if self.closed:  # the window is gone: nobody to tell
            return
        if job in self.jobs:
            self.jobs.remove(job)
        self._detached = [j for j in self._detached if j._thread.is_alive()]
        if job.state == "cancelled" and job._thread.is_alive():
            self._detached.append(job)
        if job.state == "cancelled":
            self.message.emit(f"{job.label}: cancelled")
        self.changed.emit()

    @property
    def active(self) -> list[Job]:
        return [j for j in self.jobs if j.active]

    def cancel_all(self) -> None:
        for job in list(self.jobs):
            if job.cancellable:
                job.cancel()

    def close(self) -> None:
        """Cancel everything and drop later results (the window is closing)."""
        for job in list(self.jobs):
            job._cancel.set()
        self.closed = True
        self._left = [j for j in self.jobs + self._detached if j._thread.is_alive()]
        self.jobs.clear()

    def join(self, timeout_s: float) -> bool:
        """After :meth:`close`: wait up to ``timeout_s`` in all for the threads of the jobs
        that were running (a process must not exit while one is inside OpenCL: pocl's
        threads then abort it); True if all ended."""
        end = time.perf_counter() + timeout_s
        for job in self._left:
            job.wait(max(end - time.perf_counter(), 0.0))
        return not any(j._thread.is_alive() for j in self._left)
