"""MuJoCo's data as compiled code reaches it, and the registries through which one compiled
callback serves many models. Shared by the drop's callback (``controllers.compiled``), the
rolling callback (``mtbmj.rolling.callback_compiled``) and the bike's (``mtbmj.bike.callback_compiled``).

* ``mjdata_layout``: the byte offsets of the ``mjData`` pointer fields a callback reads and
  writes, from mujoco's own struct description (``mujoco.introspect``, generated from its headers)
  laid out with ctypes; ``check_layout`` checks them against the live arrays of a model (pointer
  values equal to the numpy arrays' addresses, and a sentinel written through the pointer read back
  through numpy), once per process (``verify``).
* The numba intrinsics the callbacks need: an address from a pointer and back, a pointer field of a
  struct, an atomic counter, a small buffer on the native stack; and ``find_slot``, the registry
  lookup every compiled dispatcher makes.
* ``Registry``: slots of per-model rows (numpy arrays that are never reallocated) and a header a
  compiled dispatcher reads through an external symbol, so no address is baked into its code and it
  is cached on disk like the kernels. A dispatcher looks the ``mjModel*`` it is called with up in
  its registry (``find_slot``, the one lookup of every compiled callback) and leaves every other
  model alone; a slot is freed when its callback object is
  collected (the callback keeps its model alive, so the address cannot be reused meanwhile).
"""
from __future__ import annotations

import ctypes
import os
import threading

import mujoco
import numpy as np

from mtbmj.controllers.jit import kernel, numba
from mtbmj.controllers.lawcodes import STACK_DEPTH

MJDATA_FIELDS = ("qpos", "qvel", "act", "ctrl", "qfrc_applied")

_SCALARS = {
    "mjtNum": ctypes.c_double, "double": ctypes.c_double, "float": ctypes.c_float, "int": ctypes.c_int,
    "unsigned int": ctypes.c_uint, "mjtSize": ctypes.c_int64, "int64_t": ctypes.c_int64,
    "uint64_t": ctypes.c_uint64, "size_t": ctypes.c_size_t, "uintptr_t": ctypes.c_size_t,
    "mjtBool": ctypes.c_ubyte, "mjtByte": ctypes.c_ubyte, "char": ctypes.c_char,
}
_STRUCT_CACHE: dict = {}
_LAYOUT: dict | None = None


def _ctype(t):
    from mujoco.introspect import ast_nodes, structs

    if isinstance(t, ast_nodes.PointerType):
        return ctypes.c_void_p
    if isinstance(t, ast_nodes.ArrayType):
        return _ctype(t.inner_type) * int(np.prod(t.extents))
    if t.name in _SCALARS:
        return _SCALARS[t.name]
    if t.name in structs.STRUCTS:
        return _struct(t.name)
    raise TypeError(f"no ctypes equivalent for {t.name!r} in mujoco's struct description")


def _struct(name: str):
    from mujoco.introspect import ast_nodes, structs

    if name not in _STRUCT_CACHE:
        fields = []
        for f in structs.STRUCTS[name].fields:
            if not isinstance(f, ast_nodes.StructFieldDecl):
                raise TypeError(f"{name}: anonymous struct/union members are not supported")
            fields.append((f.name, _ctype(f.type)))
        _STRUCT_CACHE[name] = type(name, (ctypes.Structure,), {"_fields_": fields})
    return _STRUCT_CACHE[name]


def mjdata_layout() -> dict:
    """Byte offsets in ``mjData`` of the pointer fields the callback uses (and of ``time``, for
    the check), laid out with ctypes from ``mujoco.introspect`` (mujoco's header description)."""
    global _LAYOUT
    if _LAYOUT is None:
        s = _struct("mjData")
        _LAYOUT = {name: getattr(s, name).offset for name in MJDATA_FIELDS + ("time",)}
    return dict(_LAYOUT)


def check_layout(model, layout: dict | None = None) -> None:
    """Check the offsets against a live ``MjData`` of ``model``: each pointer field holds the address
    of the numpy array mujoco exposes, and a sentinel written through it is read back by numpy.
    Raises RuntimeError on any mismatch."""
    layout = mjdata_layout() if layout is None else layout
    data = mujoco.MjData(model)
    data.time = 0.123456789
    base = data._address
    if ctypes.c_double.from_address(base + layout["time"]).value != data.time:
        raise RuntimeError("mjData layout check failed: 'time' is not where mujoco's struct description puts it")
    for name in MJDATA_FIELDS:
        array = getattr(data, name)
        pointer = ctypes.c_void_p.from_address(base + layout[name]).value
        if array.size == 0:
            continue
        if pointer != array.ctypes.data:
            raise RuntimeError(f"mjData layout check failed: pointer field {name!r} at byte {layout[name]} "
                               f"does not hold the address of data.{name}")
        cell = ctypes.c_double.from_address(pointer + 8 * (array.size - 1))
        old = float(array.flat[-1])
        cell.value = 1234.5678
        ok = array.flat[-1] == 1234.5678
        cell.value = old
        if not ok:
            raise RuntimeError(f"mjData layout check failed: a sentinel written through {name!r} was not read back")


_VERIFIED: dict = {}  # the result of the live layout check, once per process


def verify(model) -> str | None:
    """None when the layout holds for a live ``MjData`` of ``model`` (checked once per process),
    else why the compiled path cannot run."""
    with _VERIFY_LOCK:
        if "reason" not in _VERIFIED:
            try:
                check_layout(model)
                _VERIFIED["reason"] = None
            except RuntimeError as error:
                _VERIFIED["reason"] = f"compiled force laws unavailable ({error}): using the Python force laws"
        return _VERIFIED["reason"]


_VERIFY_LOCK = threading.Lock()


def verified_reason() -> str | None:
    """What ``verify`` found, if it ran (None: it passed, or it has not run yet)."""
    return _VERIFIED.get("reason")


class Registry:
    """The rows a compiled dispatcher serves, one slot per live callback object.

    ``tables`` maps a name to (width, dtype): one (slots x width) array each; the first table's
    column 0 holds the slot's ``mjModel*`` address (0: free or retired). The header, read by the
    dispatcher through ``reader()`` (an intrinsic bound to the external symbol ``symbol``), holds
    ``USED`` (slots in use, a high-water mark), each table's address, and the offset of each of
    ``fields`` in ``mjData`` (filled by ``bind_layout``). ``index[name]`` is a header entry."""

    def __init__(self, symbol: str, slots: int, tables: dict, fields: tuple[str, ...]):
        self.symbol, self.slots = symbol, slots
        self.tables = {name: np.zeros((slots, width), dtype=dtype) for name, (width, dtype) in tables.items()}
        self.first = next(iter(self.tables.values()))
        names = ("used", *self.tables, *fields)
        self.index = {name: i for i, name in enumerate(names)}
        self.fields = fields
        self.header = np.zeros(len(names), dtype=np.int64)
        for name, table in self.tables.items():
            self.header[self.index[name]] = table.ctypes.data
        self.owned = np.zeros(slots, dtype=bool)  # slot held by a live callback (served or retired)
        # re-entrant: a callback collected by the garbage collector frees its slot (weakref.finalize)
        # wherever the collector runs, also inside a registry operation of this thread
        self.lock = threading.RLock()
        # A process forked while another of its threads holds the lock (a finalizer the collector
        # ran in that thread: a sweep's table-library import, the test runner's I/O thread) gave a
        # child whose first claim waited for ever: the thread that held it is not copied. So a fork
        # waits for the registry to be free and forks with it held, released on both sides.
        os.register_at_fork(before=self.lock.acquire, after_in_parent=self.lock.release,
                            after_in_child=self.lock.release)
        self._reader = None
        if numba is not None:
            import llvmlite.binding as llvm

            llvm.add_symbol(symbol, self.header.ctypes.data)

    def bind_layout(self, layout: dict) -> None:
        for name in self.fields:
            self.header[self.index[name]] = layout[name]

    def reader(self):
        """The intrinsic ``read(i)``: header entry i, for the compiled dispatcher."""
        if self._reader is None:
            self._reader = registry_reader(self.symbol, self.header.size)
        return self._reader

    def claim(self, model_address: int, rows: dict, what: str) -> int:
        """A free slot filled with ``rows`` (table name -> values for the row's start) and made live
        for ``model_address``, retiring older slots of that model. Raises RuntimeError when full."""
        with self.lock:
            free = np.flatnonzero(~self.owned)
            if not free.size:
                raise RuntimeError(f"more than {self.slots} {what} alive at once")
            slot = int(free[0])
            self.owned[slot] = True
            first = self.first
            first[first[:, 0] == model_address, 0] = 0  # retire older ones of this model
            for name, values in rows.items():
                table = self.tables[name]
                table[slot] = 0
                table[slot, : len(values)] = values
            first[slot, 0] = 0
            first[slot, 0] = model_address  # last: the slot goes live complete
            used = self.index["used"]
            self.header[used] = max(self.header[used], slot + 1)
            return slot

    def release(self, slot: int) -> None:
        with self.lock:
            self.first[slot, 0] = 0  # first: the dispatcher stops serving the slot
            for table in self.tables.values():
                table[slot] = 0
            self.owned[slot] = False
            used = self.index["used"]
            while self.header[used] > 0 and not self.owned[self.header[used] - 1]:
                self.header[used] -= 1

    def live(self, slot: int, model_address: int) -> bool:
        return bool(self.owned[slot]) and self.first[slot, 0] == model_address


if numba is not None:
    from llvmlite import ir
    from numba import types as t
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def address_of(typingctx, pointer):
        """voidptr -> integer address."""
        def codegen(context, builder, signature, args):
            return builder.ptrtoint(args[0], context.get_value_type(t.intp))
        return t.intp(t.voidptr), codegen

    @intrinsic
    def f64_pointer(typingctx, address):
        """integer address -> double*."""
        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(t.CPointer(t.float64)))
        return t.CPointer(t.float64)(t.intp), codegen

    @intrinsic
    def i64_pointer(typingctx, address):
        """integer address -> int64*."""
        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(t.CPointer(t.int64)))
        return t.CPointer(t.int64)(t.intp), codegen

    @intrinsic
    def pointer_field(typingctx, base, offset):
        """The double* stored at byte ``offset`` of the struct at ``base`` (an mjData pointer field)."""
        def codegen(context, builder, signature, args):
            struct, at = args
            slot_address = builder.add(builder.ptrtoint(struct, context.get_value_type(t.intp)), at)
            value = builder.load(builder.inttoptr(slot_address, context.get_value_type(t.CPointer(t.intp))))
            return builder.inttoptr(value, context.get_value_type(t.CPointer(t.float64)))
        return t.CPointer(t.float64)(t.voidptr, t.intp), codegen

    @intrinsic
    def atomic_increment(typingctx, pointer):
        """*pointer += 1, atomically (the per-slot call counter; threads share it)."""
        def codegen(context, builder, signature, args):
            builder.atomic_rmw("add", args[0], ir.Constant(ir.IntType(64), 1), "monotonic")
            return context.get_dummy_value()
        return t.void(t.CPointer(t.int64)), codegen

    @intrinsic
    def stack_buffer(typingctx):
        """A double[STACK_DEPTH] on the native stack (no allocation per call)."""
        def codegen(context, builder, signature, args):
            return cgutils.alloca_once(builder, ir.DoubleType(), size=STACK_DEPTH)
        return t.CPointer(t.float64)(), codegen

    @kernel
    def find_slot(table, used, width, model):
        """The slot of a registry whose row holds ``model`` (an ``mjModel*`` address) in column 0 of
        its first table (int64, ``width`` wide, at address ``table``), among the first ``used``; -1
        when none does (a model that is not one of the registry's). Every compiled dispatcher looks
        its model up here (``Registry``)."""
        rows = i64_pointer(table)
        for slot in range(used):
            if rows[slot * width] == model:
                return slot
        return -1


    def registry_reader(symbol: str, width: int):
        """An intrinsic reading entry ``index`` of the int64[width] header bound to ``symbol``."""
        @intrinsic
        def read(typingctx, index):
            def codegen(context, builder, signature, args):
                module = builder.module
                table = ir.ArrayType(ir.IntType(64), width)
                try:
                    symbol_value = module.get_global(symbol)
                except KeyError:
                    symbol_value = ir.GlobalVariable(module, table, symbol)
                    symbol_value.linkage = "external"
                at = builder.gep(symbol_value, [ir.Constant(ir.IntType(32), 0), args[0]])
                return builder.load(at)
            return t.int64(t.intp), codegen
        return read

__all__ = ["MJDATA_FIELDS", "mjdata_layout", "check_layout", "verify", "verified_reason", "Registry"]
