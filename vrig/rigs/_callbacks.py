"""MuJoCo's global callback slots shared per simulation context (issue 14, item 3).

MuJoCo has one process-wide function pointer per callback (``mjcb_control``, ``mjcb_passive``,
``mjcb_sensor``, ``mjcb_act_dyn``). A :class:`Hook` owns one slot for vrig: its compiled callback looks the
``mjData`` it is called with up in a small table of (data address, context address) pairs — one
entry per live rig run — and calls the element code with that rig's context; for any other
``mjData`` it chains to the callback that was installed before vrig's (a C callback: called
from compiled code; a Python callable: suspended while a vrig context is live). The slot is
taken when the first context is added and the earlier callback restored when the last one is
removed. The raw-pointer intrinsics the compiled callbacks need live here too. Users:
:mod:`vrig.rigs.hydraulics` (control), :mod:`vrig.rigs.gas_spring` (passive, sensor) and
:mod:`vrig.rigs.damper` (act_dyn: the series compliance of a damper; it chains the previous
callback with its own ``mjtNum f(m, d, id)`` call).
"""

from __future__ import annotations

import contextlib
import ctypes
import threading

import mujoco
import numba as nb
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import intrinsic

MAX_LIVE = 64
"""Most rig runs live at once per callback slot (one table entry each)."""

# Compiled helpers: raw pointers and calls through a function pointer (the chained callback).
@intrinsic
def _as_pointer(typingctx, address):
    sig = types.voidptr(address)

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], cgutils.voidptr_t)

    return sig, codegen


def _record_pointer(record):
    """A compiled ``f(address) -> record*`` for a numba record type (``nb.carray(f(a), n)`` is
    then an array of those records)."""

    @intrinsic
    def _pointer(typingctx, address):
        sig = types.CPointer(record)(address)

        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(signature.return_type))

        return sig, codegen

    return _pointer




@intrinsic
def _address(typingctx, pointer):
    """The integer address of a ``void*``."""
    sig = types.int64(pointer)

    def codegen(context, builder, signature, args):
        return builder.ptrtoint(args[0], ir.IntType(64))

    return sig, codegen


@intrinsic
def _call_generic(typingctx, function, m, d):
    """Call the C function at address ``function`` as ``void f(const mjModel*, mjData*)``."""
    sig = types.void(function, m, d)

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(ir.VoidType(), [cgutils.voidptr_t, cgutils.voidptr_t])
        builder.call(builder.inttoptr(args[0], fnty.as_pointer()), [args[1], args[2]])
        return context.get_dummy_value()

    return sig, codegen


@intrinsic
def _call_sensor(typingctx, function, m, d, stage):
    """Call the C function at address ``function`` as ``void f(const mjModel*, mjData*, int)``."""
    sig = types.void(function, m, d, stage)

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(
            ir.VoidType(), [cgutils.voidptr_t, cgutils.voidptr_t, ir.IntType(32)]
        )
        builder.call(builder.inttoptr(args[0], fnty.as_pointer()), list(args[1:]))
        return context.get_dummy_value()

    return sig, codegen


@nb.njit(inline="always")
def _lookup(table_address, d):  # pragma: no cover - compiled
    """The context address registered for the mjData ``d`` in a :class:`Hook` table, or 0."""
    table = nb.carray(_as_pointer(table_address), (MAX_LIVE + 1, 2), dtype=np.int64)
    key = _address(d)
    for i in range(1, MAX_LIVE + 1):
        if table[i, 0] == key:
            return table[i, 1]
    return 0


@nb.njit(inline="always")
def _context_or_chain(table_address, m, d):  # pragma: no cover - compiled
    """The context address of ``d`` in a hook's table; 0 (after calling the callback that was
    installed before vrig's, if any) for an mjData that is not vrig's."""
    address = _lookup(table_address, d)
    if address == 0:
        previous = nb.carray(_as_pointer(table_address), (1,), dtype=np.int64)[0]
        if previous != 0:
            _call_generic(previous, m, d)
    return address


class Hook:
    """vrig's compiled callback on one of MuJoCo's global hooks (``mjcb_control``,
    ``mjcb_passive``, ``mjcb_sensor``), with a per-mjData registry of contexts.

    The compiled callback is built by ``build(table_address)``; it looks up the mjData it is
    called with in a fixed table (row 0: the address of the previous C callback, 0 for none;
    rows 1..MAX_LIVE: (mjData address, context address)) and, for an mjData that is not vrig's,
    calls the previous callback (:func:`_call_generic`) or does nothing.

    The hook is installed when the first context is added and the previous callback is restored
    when the last one is removed, so a user's own callback is never clobbered between runs. The
    previous callback is chained from compiled code when it is a C function (a ``ctypes``
    function pointer, e.g. a numba ``cfunc``'s ``.ctypes``). A plain Python callable cannot be
    called from compiled code without the binding's own MjModel/MjData wrappers: it is not
    chained, i.e. it is suspended while a vrig context is live (in one thread nothing else steps
    then; another thread stepping the user's model meanwhile would not see it) and restored
    after. If the user replaces vrig's callback while a context is live, vrig leaves theirs in
    place at removal.

    Table writes happen under a lock; a slot is filled context-first and cleared key-first, so a
    callback running in another thread (``mujoco.rollout`` releases the GIL) only ever matches
    its own, stable, entry.
    """

    def __init__(self, name: str, build):
        self.name = name
        self._get = getattr(mujoco, f"get_mjcb_{name}")
        self._set = getattr(mujoco, f"set_mjcb_{name}")
        self._build = build
        self.table = np.zeros((MAX_LIVE + 1, 2), dtype=np.int64)
        self._callback = None  # the compiled cfunc (built on first use)
        self._previous = None  # what was installed before vrig's callback
        self._live = {}  # mjData address -> (slot, objects kept alive while registered)
        self._lock = threading.Lock()

    @property
    def installed(self) -> bool:
        """Whether vrig's callback is the one MuJoCo calls."""
        return self._callback is not None and self._get() is self._callback.ctypes

    def add(self, data: mujoco.MjData, context: np.ndarray, *keep) -> None:
        """Register ``context`` (a structured array; its address is what the callback gets) for
        ``data``, replacing an earlier one for it; ``keep``: more objects to keep alive."""
        key = data._address
        with self._lock:
            if self._callback is None:
                self._callback = self._build(self.table.ctypes.data)
            if key in self._live:
                slot = self._live[key][0]
            else:
                free = np.flatnonzero(self.table[1:, 0] == 0)
                if free.size == 0:
                    raise RuntimeError(
                        f"more than {MAX_LIVE} MjData have a live vrig {self.name} callback "
                        "context: remove some first"
                    )
                slot = int(free[0]) + 1
            if not self._live and not self.installed:
                self._previous = self._get()
                self.table[0, 0] = _c_address(self._previous)
                self._set(self._callback.ctypes)
            self.table[slot, 1] = context.ctypes.data  # context first, then the key
            self.table[slot, 0] = key
            self._live[key] = (slot, data, context, keep)

    def remove(self, data: mujoco.MjData | None = None) -> None:
        """Remove the context of ``data`` (every context for None); with none left, restore
        the previous callback (unless someone replaced vrig's meanwhile)."""
        with self._lock:
            keys = list(self._live) if data is None else [data._address]
            for key in keys:
                entry = self._live.pop(key, None)
                if entry is not None:
                    self.table[entry[0], 0] = 0  # the key first
                    self.table[entry[0], 1] = 0
            if not self._live and self._callback is not None:
                if self.installed:
                    self._set(self._previous)
                self._previous = None
                self.table[0, 0] = 0

    def _take_foreign(self):
        """Stop calling the foreign callback (a user's); returns what to give back."""
        with self._lock:
            if self.installed:  # vrig's own hook is live (runs in other threads): stop chaining
                saved = ("chained", int(self.table[0, 0]))
                self.table[0, 0] = 0
                return saved
            saved = ("slot", self._get())
            if saved[1] is not None:
                self._set(None)
            return saved

    def _give_back(self, saved) -> None:
        """Undo :meth:`_take_foreign` (whatever vrig's own hook did meanwhile)."""
        kind, value = saved
        with self._lock:
            if self.installed:  # vrig's hook live now: the foreign callback is its previous one
                if kind == "chained":
                    self.table[0, 0] = value
                elif value is not None and self._previous is None:
                    self._previous = value
                    self.table[0, 0] = _c_address(value)
            elif kind == "slot" and value is not None and self._get() is None:
                self._set(value)

    @contextlib.contextmanager
    def foreign_suspended(self):
        """A ``with`` block in which this slot calls no callback but vrig's own registered
        contexts: the user's callback (a Python callable or a C function) is neither called
        nor lost, and is back in place (or chained again) afterwards."""
        saved = self._take_foreign()
        try:
            yield
        finally:
            self._give_back(saved)

    def context_of(self, data: mujoco.MjData):
        """The registered context of ``data``, or None."""
        entry = self._live.get(data._address)
        return None if entry is None else entry[2]


def _c_address(callback) -> int:
    """The C address of a callback ``mujoco.get_mjcb_*`` returned: a ctypes function pointer's;
    0 for None or a Python callable (not chained, see :class:`Hook`)."""
    if isinstance(callback, ctypes._CFuncPtr):
        return int(ctypes.cast(callback, ctypes.c_void_p).value or 0)
    return 0


@contextlib.contextmanager
def foreign_callbacks_suspended(*hooks: Hook):
    """Suspend every foreign callback of ``hooks`` (see :meth:`Hook.foreign_suspended`).

    For the model compilation and the load-time forward passes of a rig: MuJoCo's compiler runs
    the model once (``mj_setConst``) with whatever callbacks are installed, so a user's Python
    ``mjcb_control`` made the compilation itself fail ("Python exception raised", the binding
    cannot wrap a model that does not exist yet), and a C callback would run on vrig's model.

    Parameters
    ----------
    *hooks : Hook
        The hooks whose slots to keep free of foreign callbacks.
    """
    with contextlib.ExitStack() as stack:
        for hook in hooks:
            stack.enter_context(hook.foreign_suspended())
        yield
