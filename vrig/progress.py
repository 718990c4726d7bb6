"""Progress of long phases on stderr: bars and one-line status messages.

The library is quiet by default (tests, the gymnasium environments, the benchmark workers); a
caller that wants progress switches it on for a block::

    with vrig.progress.enabled():          # on, whatever stderr is
        vrig.reconstruct(rig, desired)
    with vrig.progress.enabled(None):      # on when stderr is a terminal (what `vrig` uses)
        ...

Inside such a block, :func:`pseudo_field <vrig.desired.pseudo_field.pseudo_field>` reports each level it tries,
the drive-iteration engine says what it identifies and fits, and a MuJoCo rig run shows a bar
over its chunks when it lasts longer than :data:`RUN_BAR_DELAY_S`. The switch is a context
variable: it holds for the thread (and task) that set it. Progress never changes a number.

The bars of vrig's loops come from :func:`bar` (a command's loop over rig runs too), so one rule
holds everywhere: nothing is written unless progress is on (for ``vrig``: the ``VRIG_PROGRESS``
variable, by default on a terminal only), no carriage-return bars in a redirected stderr.
The bars are plain text (``tqdm.std``, never ``tqdm.auto``): inside a Jupyter kernel
``tqdm.auto`` wants ipywidgets and warns ("IProgress not found") on first use, a warning box in
every executed notebook that imports vrig.
"""

from __future__ import annotations

import contextlib
import contextvars
import sys

__all__ = ["RUN_BAR_DELAY_S", "bar", "enabled", "enabled_if", "is_enabled", "status"]

RUN_BAR_DELAY_S = 2.0
"""A rig run shows its chunk bar only once it has taken this long [s] (short runs stay silent)."""

_MODE: contextvars.ContextVar[bool | None] = contextvars.ContextVar("vrig_progress", default=False)


@contextlib.contextmanager
def enabled(on: bool | None = True):
    """Switch progress output on (``True``), off (``False``) or on when stderr is a terminal
    (``None``) inside the ``with`` block.

    Parameters
    ----------
    on : bool or None
        The mode inside the block (default ``True``).
    """
    token = _MODE.set(on)
    try:
        yield
    finally:
        _MODE.reset(token)


def enabled_if(flag: bool):
    """:func:`enabled` when ``flag`` is true and progress is off here; otherwise leave the mode
    as it is (a caller's ``progress=True`` switches it on, never overrides an outer choice).

    Parameters
    ----------
    flag : bool
        The caller's ``progress`` argument.
    """
    if flag and _MODE.get() is False:
        return enabled(True)
    return contextlib.nullcontext()


def is_enabled() -> bool:
    """Whether progress is shown here and now (the mode, and for ``None`` whether stderr is a
    terminal)."""
    mode = _MODE.get()
    if mode is None:
        isatty = getattr(sys.stderr, "isatty", None)
        return bool(isatty and isatty())
    return bool(mode)


def status(text: str) -> None:
    """One status line on stderr (``vrig: text``) when progress is enabled; nothing otherwise.

    Parameters
    ----------
    text : str
        What is being done, e.g. ``"identifying: IDDRV 30 s -> rig"``.
    """
    if is_enabled():
        from tqdm import tqdm

        tqdm.write(f"vrig: {text}", file=sys.stderr)
        sys.stderr.flush()


def bar(total=None, *, desc: str = "", unit: str = "it", delay: float = 0.0, initial: int = 0):
    """A tqdm bar on stderr, disabled unless progress is enabled (:func:`enabled`).

    Parameters
    ----------
    total : int, optional
        Number of steps (``None``: a counter).
    desc : str
        The bar's label.
    unit : str
        What one step is.
    delay : float
        Show the bar only after this many seconds (``tqdm(delay=...)``).
    initial : int
        Steps already done when the bar starts (e.g. a first run made before the loop).

    Returns
    -------
    tqdm.tqdm
    """
    from tqdm import tqdm

    return tqdm(
        total=total,
        desc=desc,
        unit=unit,
        delay=delay,
        initial=initial,
        leave=False,
        file=sys.stderr,
        disable=not is_enabled(),
    )
