"""Slot columns of a :class:`~hcomc.sim.log.SimulationLog`: a vehicle that left the road
hands its column on to the next vehicle that enters.

A run's log is read as ``T`` rows x ``N`` vehicles, but only the vehicles on the road at a
row have anything to store there: in a 1-hour run about 1 % of the (row, vehicle) cells.
The engine's log therefore stores its cells in ``S`` *slot columns* (S = the most vehicles
on the road at once, not N), and three small tables say which vehicle a slot holds when:

=========== ======== ========================================================================
array       shape    meaning
=========== ======== ========================================================================
``slot``    (N,)     column of vehicle i, -1 when it has not been logged yet
``span``    (N, 2)   rows ``[first, end)`` vehicle i holds its column; ``end`` = :data:`OPEN`
                     while it is on the road
``owner``   (S,)     vehicle holding slot s now, -1 when free
=========== ======== ========================================================================

At each logged row the vehicles that left since the last one free their slot (their span
ends at this row) and each vehicle on the road without a slot takes the lowest free one, in
vehicle order (:func:`claim_slots`). Cells of a slot outside its holders' spans keep the
log's fill value, so vehicle i's cell at row k is the slot cell when k lies in its span and
the fill value otherwise (:func:`cell_of`). :class:`VehicleCells` gives the (T, N) view that
readers index like the plain array it replaces (its reads gather the cells asked for with
:func:`gather_cells`); kernels that visit many rows read the stored cells themselves, row by
row through :func:`active_columns`, the columns of the vehicles on the road.

A log made from plain (T, N) arrays (:meth:`SimulationLog.allocate` without ``slots``, or
the constructor) keeps one column per vehicle: ``slot = arange(N)``, every span ``[0,
OPEN)``, and its ``x`` ... ``active`` are the arrays themselves.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from hcomc._jit import kernel
from hcomc.sim.log.layout import FILL

__all__ = [
    "OPEN", "VehicleCells", "active_columns", "cell_of", "claim_slots", "empty_slots",
    "gather_cells", "identity_slots", "owner_grid", "rows_of", "widen",
]  # fmt: skip

OPEN = np.iinfo(np.int64).max
"""End row of the span of a vehicle still holding its slot."""


def identity_slots(n_vehicles: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``slot, span, owner`` of a log with one column per vehicle (vehicle i in column i)."""
    slot = np.arange(n_vehicles, dtype=np.int64)
    span = np.zeros((n_vehicles, 2), dtype=np.int64)
    span[:, 1] = OPEN
    return slot, span, slot.copy()


def empty_slots(n_vehicles: int, n_slots: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``slot, span, owner`` of an empty slot-column log: no vehicle logged, every slot free."""
    return (
        np.full(n_vehicles, -1, dtype=np.int64),
        np.zeros((n_vehicles, 2), dtype=np.int64),
        np.full(n_slots, -1, dtype=np.int64),
    )


def owner_grid(slot: np.ndarray, span: np.ndarray, n_rows: int, n_slots: int) -> np.ndarray:
    """(T, S) int64: the vehicle each stored cell belongs to, -1 for none."""
    grid = np.full((n_rows, n_slots), -1, dtype=np.int64)
    for i in np.flatnonzero(slot >= 0).tolist():
        first, end = span[i]
        grid[first : min(end, n_rows), slot[i]] = i
    return grid


def widen(
    cells: dict[str, np.ndarray], owner: np.ndarray, n_slots: int
) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Slot columns ``cells`` and ``owner`` widened to ``n_slots`` columns (new ones free,
    holding the fill value); unchanged when they already have as many."""
    old = owner.size
    if n_slots <= old:
        return cells, owner
    wide = {}
    for name, store in cells.items():  # each cell written once: the old ones, then the fill
        wide[name] = np.empty((store.shape[0], n_slots), dtype=store.dtype)
        wide[name][:, :old] = store
        wide[name][:, old:] = FILL[name]
    return wide, np.concatenate([owner, np.full(n_slots - old, -1, dtype=np.int64)])


@kernel
def claim_slots(
    active: np.ndarray, slot: np.ndarray, span: np.ndarray, owner: np.ndarray, k: int
) -> bool:
    """The slot bookkeeping of log row ``k`` (see the module doc); False, changing nothing,
    when there are fewer free slots than vehicles entering (the log must grow first).

    Raises ``ValueError`` for a vehicle back on the road after its span ended (the engine
    never re-inserts a vehicle).
    """
    if _unchanged(active, owner):  # the usual row: the same vehicles as at the last
        return True
    if not _room_for_entering(active, slot, span, owner):
        return False
    for i in range(active.size):
        if slot[i] >= 0 and span[i, 1] == OPEN and not active[i]:
            span[i, 1] = k
            owner[slot[i]] = -1
    s = 0
    for i in range(active.size):
        if active[i] and slot[i] < 0:
            while owner[s] >= 0:
                s += 1
            owner[s], slot[i] = i, s
            span[i, 0], span[i, 1] = k, OPEN
    return True


@kernel(inline="always")
def _unchanged(active: np.ndarray, owner: np.ndarray) -> bool:
    """Whether the vehicles on the road are exactly those holding a slot (a vehicle holds one
    while its span is open): every holder is on the road and as many are on the road as hold
    slots. A long run's many vehicles gone are only counted, not visited."""
    held = 0
    for s in range(owner.size):
        i = owner[s]
        if i >= 0:
            if not active[i]:
                return False
            held += 1
    on_road = 0
    for i in range(active.size):
        on_road += 1 if active[i] else 0
    return on_road == held


@kernel(inline="always")
def _room_for_entering(
    active: np.ndarray, slot: np.ndarray, span: np.ndarray, owner: np.ndarray
) -> bool:
    """Whether the free slots and those of the vehicles that left suffice for the vehicles
    entering; a vehicle back on the road after its span ended raises ``ValueError``."""
    free = 0
    for s in range(owner.size):
        if owner[s] < 0:
            free += 1
    entering = 0
    for i in range(active.size):
        if slot[i] < 0:
            entering += 1 if active[i] else 0
        elif span[i, 1] == OPEN and not active[i]:
            free += 1
        elif active[i] and span[i, 1] != OPEN:
            raise ValueError("a vehicle re-entered the road after its log span ended")
    return entering <= free


@kernel(inline="always")
def cell_of(store: np.ndarray, slot: np.ndarray, span: np.ndarray, k: int, i: int) -> Any:
    """Vehicle i's cell at row k of one slot-column array ``store`` (T, S); NaN outside its
    span (for float arrays, whose fill value it is)."""
    s = slot[i]
    if s < 0 or k < span[i, 0] or k >= span[i, 1]:
        return np.nan
    return store[k, s]


@kernel
def rows_of(
    store: np.ndarray, slot: np.ndarray, span: np.ndarray, i: int, r0: int, r1: int
) -> np.ndarray:
    """Vehicle i's float cells over rows ``[r0, r1)`` (float64, NaN outside its span)."""
    out = np.empty(max(r1 - r0, 0))
    for k in range(r0, r1):
        out[k - r0] = cell_of(store, slot, span, k, i)
    return out


@kernel
def gather_cells(
    store: np.ndarray, slot: np.ndarray, span: np.ndarray, rows: np.ndarray,
    vehicles: np.ndarray, out: np.ndarray,
) -> None:  # fmt: skip
    """``out[q, j]`` = vehicle ``vehicles[j]``'s cell at row ``rows[q]`` of ``store`` (T, S)
    where the row lies in its span; other cells of ``out`` (R, K), filled by the caller with
    the fill value, are left alone. Indices must be in range and non-negative."""
    for j in range(vehicles.size):
        i = vehicles[j]
        s = slot[i]
        if s < 0:
            continue
        first, end = span[i, 0], span[i, 1]
        for q in range(rows.size):
            k = rows[q]
            if first <= k < end:
                out[q, j] = store[k, s]


@kernel
def active_columns(
    active: np.ndarray, slot: np.ndarray, span: np.ndarray, r0: int, r1: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The vehicles on the road in rows ``[r0, r1)`` of a log, row by row in vehicle order,
    and the columns their cells are stored in: ``(start, vehicle, column)``.

    Row ``r0 + k``'s vehicles are ``vehicle[start[k]:start[k + 1]]`` (ascending) and their
    cells ``store[r0 + k, column[start[k]:start[k + 1]]]`` of any stored array: exactly the
    cells where the (T, N) view of ``active`` is True. A kernel that visits the rows of a
    window so reads only the cells on the road (S per row at most, not N), in the order a
    scan of the (T, N) row would meet them. ``r1 <= T``.
    """
    n_rows = max(r1 - r0, 0)
    start = np.zeros(n_rows + 1, dtype=np.int64)
    for i in range(slot.size):
        s = slot[i]
        if s >= 0:
            for k in range(max(r0, span[i, 0]), min(r1, span[i, 1])):
                if active[k, s]:
                    start[k - r0 + 1] += 1
    for k in range(n_rows):
        start[k + 1] += start[k]
    vehicle = np.empty(start[n_rows], dtype=np.int64)
    column = np.empty(start[n_rows], dtype=np.int64)
    fill = start[:n_rows].copy()
    for i in range(slot.size):  # vehicle order: each row's entries come out ascending
        s = slot[i]
        if s >= 0:
            for k in range(max(r0, span[i, 0]), min(r1, span[i, 1])):
                if active[k, s]:
                    vehicle[fill[k - r0]], column[fill[k - r0]] = i, s
                    fill[k - r0] += 1
    return start, vehicle, column


class VehicleCells(np.lib.mixins.NDArrayOperatorsMixin):
    """Read-only (T, N) view of one slot-column array: indexing, numpy functions and
    operators behave as on the plain (T, N) array it stands for.

    Indexing gathers only the cells asked for (``log.x[k]``, ``log.v[r0:r1, i]``,
    ``log.x[rows, ids]`` ...); anything else (``np.where(log.active, ...)``, methods such as
    ``.any(axis=0)``) builds the whole (T, N) array first.
    """

    __array_priority__ = 20

    def __init__(
        self, store: np.ndarray, slot: np.ndarray, span: np.ndarray, fill: float | int | bool
    ) -> None:
        self._store, self._slot, self._span, self._fill = store, slot, span, fill
        self.shape: tuple[int, int] = (store.shape[0], slot.size)
        self.dtype: np.dtype = store.dtype

    ndim = 2

    @property
    def size(self) -> int:
        return self.shape[0] * self.shape[1]

    def __len__(self) -> int:
        return self.shape[0]

    def __repr__(self) -> str:
        return f"VehicleCells(shape={self.shape}, dtype={self.dtype})"

    def __getitem__(self, key: Any) -> Any:
        key = _plain(key)
        if isinstance(key, int | np.integer):  # log.x[k]: one row, the commonest read
            return self._row(int(key))
        if isinstance(key, tuple) and len(key) == 2 and all(_is_int(k) for k in key):
            return self._cell(int(key[0]), int(key[1]))
        if _selects_rows(key):  # log.x[k], log.x[r0:r1], log.x[rows]: every vehicle
            return self._rows(key[0] if isinstance(key, tuple) else key)
        if _rows_and_vehicles(key):  # log.x[r0:r1, ids]: a window of a few vehicles
            return self._block(key[0], np.asarray(key[1]))
        if _rows_and_vehicle(key):  # log.x[r0:r1, i]: one vehicle's cells
            return self._block(key[0], np.array([key[1]]))[:, 0]
        n_rows, n_vehicles = self.shape
        idx = np.int32 if max(n_rows, n_vehicles) < 2**31 else np.int64
        rows = np.broadcast_to(np.arange(n_rows, dtype=idx)[:, None], self.shape)[key]
        vehicles = np.broadcast_to(np.arange(n_vehicles, dtype=idx)[None, :], self.shape)[key]
        slots = self._slot[vehicles]
        inside = (slots >= 0) & (rows >= self._span[vehicles, 0]) & (rows < self._span[vehicles, 1])
        return self._gather(rows, slots, inside)

    def _cell(self, k: int, i: int) -> Any:
        """Vehicle i's cell at row k (negative indices count from the end)."""
        (n_rows, n_vehicles), slot, span = self.shape, self._slot, self._span
        if not (-n_rows <= k < n_rows and -n_vehicles <= i < n_vehicles):
            raise IndexError(f"index ({k}, {i}) is out of bounds for shape {self.shape}")
        k, i = k % n_rows, i % n_vehicles
        if slot[i] < 0 or not span[i, 0] <= k < span[i, 1]:
            return self.dtype.type(self._fill)
        return self._store[k, slot[i]]

    def _row(self, k: int) -> np.ndarray:
        """Every vehicle's cell at row ``k`` (negative: from the end)."""
        n_rows = self.shape[0]
        if not -n_rows <= k < n_rows:
            raise IndexError(f"row {k} is out of bounds for {n_rows} rows")
        k = k + n_rows if k < 0 else k
        slot, span = self._slot, self._span
        inside = np.flatnonzero((slot >= 0) & (span[:, 0] <= k) & (span[:, 1] > k))
        out = np.full(slot.size, self._fill, dtype=self.dtype)
        out[inside] = self._store[k, slot[inside]]
        return out

    def _rows(self, key: Any) -> Any:
        """Every vehicle's cells at the rows ``key`` selects (int, slice, 1-D index)."""
        if isinstance(key, int | np.integer):
            return self._row(int(key))
        return self._block(key, np.arange(self.shape[1]))

    def _block(self, rows: Any, vehicles: np.ndarray) -> np.ndarray:
        """The cells of ``vehicles`` (1-D indices) at the rows ``rows`` selects (a slice or
        1-D indices): (R, K)."""
        rows = np.arange(self.shape[0])[rows]  # bounds checked, negatives resolved
        vehicles = np.arange(self.shape[1])[vehicles]
        out = np.full((rows.size, vehicles.size), self._fill, dtype=self.dtype)
        gather_cells(self._store, self._slot, self._span, rows, vehicles, out)
        return out

    def _gather(self, rows: np.ndarray | slice, slots: np.ndarray, inside: np.ndarray) -> Any:
        """The stored cells at ``rows`` (an index broadcast against ``slots``, or a slice of
        rows: the rows are then taken whole first, a view) and ``slots``, the fill outside
        ``inside``."""
        fill = np.array(self._fill, dtype=self.dtype)
        if self._store.shape[1] == 0:  # no column: nothing was logged
            return np.full(inside.shape, fill)[()]
        columns = np.maximum(slots, 0)
        cells = (
            self._store[rows][:, columns] if isinstance(rows, slice) else self._store[rows, columns]
        )
        out = np.where(inside, cells, fill)
        return out[()] if out.ndim == 0 else out

    def __array__(self, dtype: Any = None, copy: Any = None) -> np.ndarray:
        whole = self[:, :]
        return whole if dtype is None else whole.astype(dtype)

    def __array_ufunc__(self, ufunc: Any, method: str, *inputs: Any, **kwargs: Any) -> Any:
        return getattr(ufunc, method)(*_plain(inputs), **_plain(kwargs))

    def __array_function__(self, func: Any, types: Any, args: Any, kwargs: Any) -> Any:
        return func(*_plain(args), **_plain(kwargs))

    def __getattr__(self, name: str) -> Any:
        if name.startswith("_"):
            raise AttributeError(name)
        return getattr(np.asarray(self), name)  # e.g. .any(axis=0), .astype(float)


def _plain(x: Any) -> Any:
    """``x`` with every :class:`VehicleCells` in it (also inside tuples, lists and dicts)
    replaced by its plain array."""
    if isinstance(x, VehicleCells):
        return np.asarray(x)
    if isinstance(x, list | tuple):
        return type(x)(_plain(y) for y in x)
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    return x


def _is_int(key: Any) -> bool:
    return isinstance(key, int | np.integer) and not isinstance(key, bool | np.bool_)


def _rows_and_vehicle(key: Any) -> bool:
    """Whether ``key`` is a row slice and one vehicle index."""
    pair = isinstance(key, tuple) and len(key) == 2
    return pair and isinstance(key[0], slice) and _is_int(key[1])


def _rows_and_vehicles(key: Any) -> bool:
    """Whether ``key`` is a row slice and a 1-D integer array of vehicles."""
    if not (isinstance(key, tuple) and len(key) == 2 and isinstance(key[0], slice)):
        return False
    vehicles = key[1]
    return (
        isinstance(vehicles, np.ndarray | list)
        and np.asarray(vehicles).ndim == 1
        and np.asarray(vehicles).dtype.kind in "iu"
    )


def _selects_rows(key: Any) -> bool:
    """Whether ``key`` indexes rows only (an int, a slice or a 1-D integer array)."""
    if isinstance(key, tuple):
        if len(key) != 1:
            whole = isinstance(key[1], slice) and key[1] == slice(None)
            return len(key) == 2 and whole and _selects_rows(key[0])
        key = key[0]
    if isinstance(key, int | np.integer | slice):
        return True
    return (
        isinstance(key, np.ndarray | list)
        and np.asarray(key).ndim == 1
        and (np.asarray(key).dtype.kind in "iu")
    )
