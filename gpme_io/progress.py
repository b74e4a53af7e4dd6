"""A run's progress on stderr, drawn from the engine's events (gpme_core.progress): a tqdm
bar on a terminal; elsewhere (CI logs, files) at most one line per tenth of the run and per
LOG_LINE_SECONDS, so a log never gets hundreds of progress lines (a short run: none).  The
first call's numba compilation is announced on both.  `gpme simulate` and `gpme verify`
pass it to the runs (gpme_io.runs.simulate_scenario)."""
import sys

from tqdm import tqdm

from gpme_core.progress import Compiling, Progress

# s between two progress lines when stderr is not a terminal
LOG_LINE_SECONDS = 30.0
# bar updates: every this many steps, and at the end (tqdm redraws at most once a second)
BAR_EVERY = 1000


class TerminalProgress:
    """A gpme_core.progress.ProgressCallback writing to stderr; one object serves any
    number of runs in turn (a run's state is reset by its ``finished`` event)."""

    def __init__(self):
        self._run = None

    def __call__(self, event):
        if isinstance(event, Compiling):
            _compiling(event)
        elif isinstance(event, Progress):
            if self._run is None:
                self._run = _RunProgress(event)
            self._run.update(event)
            if event.finished:
                self._run.close()
                self._run = None


def progress_callback(progress):
    """The callback for simulate's ``progress`` from a command's choice: True gives a
    :class:`TerminalProgress`, False or None no progress, a callable is returned as it is."""
    if progress is True:
        return TerminalProgress()
    if progress is False or progress is None:
        return None
    return progress


def _compiling(event):
    if not event.finished:
        print("compiling the numba kernels (first call in this process; cached on disk "
              "for the next) ...", file=sys.stderr, flush=True)
    else:
        print(f"  compiled in {event.wall_s:.1f} s", file=sys.stderr, flush=True)


class _RunProgress:
    """One run's bar (on a terminal) or lines (elsewhere), from its first event on."""

    def __init__(self, first):
        self.total, self.t_end, self.label = first.total, first.t_end, first.method
        self.bar, self.lines, self.next_tenth = None, True, 1
        self.done, self.last_line_s = 0, 0.0
        if sys.stderr.isatty():
            self.bar = tqdm(total=self.total, unit="step", desc=self.label, leave=False,
                            mininterval=1.0)
            self.lines = False

    def update(self, event):
        done = event.done
        if self.bar is not None:
            if done - self.done >= BAR_EVERY or done == self.total:
                self.bar.update(done - self.done)
                self.done = done
        elif self.lines and done * 10 >= self.next_tenth * self.total:
            self.next_tenth = int(done * 10 // self.total) + 1
            if event.wall_s - self.last_line_s < LOG_LINE_SECONDS:
                return
            self.last_line_s = event.wall_s
            left = event.wall_s * (self.total - done) / max(done, 1)
            print(f"  {self.label}: {100 * done / self.total:3.0f} % (t = "
                  f"{event.t:.4g} of {self.t_end:.4g} s), "
                  f"{event.wall_s:.0f} s elapsed, ~{left:.0f} s left", file=sys.stderr,
                  flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()
