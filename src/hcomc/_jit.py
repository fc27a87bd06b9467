"""How hcomc compiles its kernels: one decorator, one policy.

Every compiled function of hcomc is declared with :data:`kernel`, numba's ``njit`` with

* ``cache=True``: compiled once per machine and loaded from ``__pycache__`` afterwards;
* ``error_model="numpy"``: a floating-point division by zero gives inf or NaN, as it does in
  numpy, instead of raising ``ZeroDivisionError``. Every other result is the same under both
  models; numpy's spares the test for zero before each division in the kernels' inner
  loops.

Use it bare (``@kernel``) or with numba's other options (``@kernel(inline="always")``,
``@kernel(parallel=True)``).

**The cache follows the sources each kernel depends on.** numba judges a cached function
fresh when the file that defines it is unchanged, but a compiled function carries the code of
the functions it calls: after an edit of a car-following equation, the simulation step
(defined in other files) would go on running the old model. hcomc's kernels are therefore
cached with the stamp of their own module (:func:`hcomc._stamp.module_stamp`: its source and
the stamps of the hcomc modules it imports when loaded), in their freshness and in their cache
files' names (:class:`PackageCacheLocator`): an edit recompiles on first use the kernels of the
edited module and of the modules that import it, and nothing else; an edit of the command
line, the experiments, the figures or a controller's Python code recompiles nothing.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Any, TypeVar, overload

import numpy as np
from numba import carray, njit, types
from numba.core import caching, cgutils
from numba.extending import intrinsic

PACKAGE = Path(__file__).resolve().parent
"""The directory of the hcomc package, whose sources the kernels' cache stamps."""

TAG_LENGTH = 16
"""How many hex digits of a stamp go into cache file names and markers."""


@functools.cache
def source_stamp(package: Path = PACKAGE) -> str:
    """Fingerprint of every kernel module's stamp (:func:`hcomc._stamp.fingerprint`; once per
    process): it changes exactly when some kernel's cache goes stale."""
    from hcomc._stamp import fingerprint

    return fingerprint(package)


def stamp_tag(package: Path = PACKAGE) -> str:
    """The part of :func:`source_stamp` in the name of the compiled-cache marker."""
    return source_stamp(package)[:TAG_LENGTH]


def file_stamp(py_file: Path, package: Path = PACKAGE) -> str:
    """The stamp of the module in ``py_file`` (:func:`hcomc._stamp.module_stamp`)."""
    from hcomc._stamp import module_name, module_stamp

    return module_stamp(module_name(py_file.resolve(), package), package)


def remove_stale_caches(package: Path = PACKAGE) -> int:
    """Delete the cache files of ``package``'s kernels in its ``__pycache__`` directories that
    were written for other sources (their names lack their module's current stamp); returns
    how many. They are never read again, and a full cache takes tens of megabytes."""
    stale = []
    for pattern in ("__pycache__/*.nbi", "__pycache__/*.nbc"):
        for path in package.rglob(pattern):
            source = path.parent.parent / f"{path.name.split('.')[0]}.py"  # numba's names
            if not source.exists() or f"-{file_stamp(source, package)[:TAG_LENGTH]}." not in (
                path.name
            ):
                stale.append(path)
    for path in stale:
        path.unlink(missing_ok=True)
    return len(stale)


class PackageCacheLocator(caching._CacheLocator):
    """numba's own cache locator for a function of the package (in ``__pycache__``, or
    ``NUMBA_CACHE_DIR``), with its module's stamp (:func:`file_stamp`) added to its
    freshness."""

    package = PACKAGE
    _numbas: tuple[Any, ...] = ()  # numba's locators, tried in its order

    def __init__(self, inner: Any, py_file: str) -> None:
        self._inner = inner
        self._stamp = file_stamp(Path(py_file), self.package)

    def __getattr__(self, name: str) -> Any:
        """Anything else numba asks (e.g. ``_py_file`` for its warning that a function
        cannot be cached) is the wrapped locator's."""
        return getattr(self._inner, name)

    def ensure_cache_path(self) -> None:
        self._inner.ensure_cache_path()

    def get_cache_path(self) -> str:
        return str(self._inner.get_cache_path())

    def get_source_stamp(self) -> Any:
        return (self._inner.get_source_stamp(), self._stamp)

    def get_disambiguator(self) -> str:
        """numba's (the function's line) and the start of the module's stamp: a cache written
        for other sources has other file names and is never opened. numba unpickles an index
        before it compares the index's stamp, and the types in an index name the modules that
        defined them, so an index left by sources whose modules have since moved would fail to
        load instead of being found stale."""
        return f"{self._inner.get_disambiguator()}-{self._stamp[:TAG_LENGTH]}"

    @classmethod
    def from_function(cls, py_func: Any, py_file: str) -> PackageCacheLocator | None:
        if not Path(py_file).resolve().is_relative_to(cls.package):
            return None  # not ours: numba's own locators take it
        for numba_locator in cls._numbas:
            inner = numba_locator.from_function(py_func, py_file)
            if inner is not None:
                return cls(inner, py_file)
        return None


def use_package_stamp(locator: type[PackageCacheLocator]) -> None:
    """Put ``locator`` before numba's cache locators (once)."""
    impl = vars(caching).get("CacheImpl") or vars(caching)["_CacheImpl"]  # older numba: private
    classes = impl._locator_classes
    if locator not in classes:
        locator._numbas = tuple(c for c in classes if not issubclass(c, PackageCacheLocator))
        classes.insert(0, locator)


use_package_stamp(PackageCacheLocator)

_Function = TypeVar("_Function", bound=Callable[..., Any])


@overload
def kernel(function: _Function, /) -> _Function: ...
@overload
def kernel(**options: Any) -> Callable[[_Function], _Function]: ...
def kernel(function: Any = None, /, **options: Any) -> Any:
    """numba's ``njit`` with hcomc's compilation policy (module docstring).

    Typed as returning the function it compiles, so that mypy checks every call of a kernel
    against the kernel's annotations (numba itself ignores them)."""
    compile_ = partial(njit, cache=True, error_model="numpy", **options)
    return compile_ if function is None else compile_(function)


@intrinsic
def _as_pointer(typingctx: Any, address: Any) -> Any:
    """The integer ``address`` as a raw data pointer (for :func:`borrow`)."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        return builder.inttoptr(args[0], cgutils.voidptr_t)

    return types.voidptr(address), codegen


@kernel(inline="always")
def borrow(a: np.ndarray) -> np.ndarray:
    """A view of the C-contiguous array ``a`` that does not own its memory.

    numba counts the references to an owning array atomically each time a compiled helper,
    inlined or not, receives it: inside a per-vehicle or per-step loop that costs about
    25 ns a call (in the HCOMC prediction's passes a quarter of their time). A borrowed view
    is not counted, so a loop can call a helper that takes arrays (a search, a neighbour
    lookup) as cheaply as the same expression written in place. The caller must keep ``a``
    alive while the view is used.
    """
    return carray(_as_pointer(a.ctypes.data), a.shape, a.dtype)  # type: ignore[call-arg]


def _borrowed_views(typingctx: Any, arrays: Any) -> Any:
    """Typing and code of :data:`borrow_all`."""
    members = getattr(arrays, "types", None)
    if members is None or not all(isinstance(t, types.Array) for t in members):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        views = []
        for k, typ in enumerate(members):
            view = context.make_array(typ)(context, builder, builder.extract_value(args[0], k))
            view.meminfo = cgutils.get_null_value(view.meminfo.type)
            view.parent = cgutils.get_null_value(view.parent.type)
            views.append(view._getvalue())
        return context.make_tuple(builder, arrays, views)

    return arrays(arrays), codegen


borrow_all: Any = intrinsic(_borrowed_views)
"""``borrow_all(arrays)`` in a kernel: the arrays of the tuple ``arrays`` as views that do
not own their memory, typed as they are (:func:`borrow` of each, for any layout), so that
their reference counts are no-ops. The caller must keep the arrays alive while the views
are used."""


__all__ = [
    "PACKAGE",
    "PackageCacheLocator",
    "borrow",
    "borrow_all",
    "file_stamp",
    "kernel",
    "source_stamp",
    "use_package_stamp",
]
