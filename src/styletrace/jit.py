"""Choosing the Dr.Jit backend before Mitsuba is imported.

The LLVM backend `dlopen`s a system libLLVM. Dr.Jit 1.5 aborts the whole process on libLLVM 15
(instruction selection fails on `fminimum`) and refuses 14, so we look for a newer library ourselves
and hand it to Dr.Jit through `DRJIT_LIBLLVM_PATH` before the first `import drjit`.
Then the variant: `cuda_ad_rgb` where CUDA works, else `llvm_ad_rgb`, unless the user chose one.

`no_collection()` keeps Python's cyclic garbage collector from running while a pass is traced and
launched (a scene freed by it in the middle of a trace made LLVM abort:
docs/design/collection_during_traces.md).
"""
from __future__ import annotations

import contextlib
import gc
import glob
import mmap
import os
import re
import sys

# re-exported: callers catch BackendError from here
from styletrace.errors import BackendError

#: Oldest libLLVM major version that Dr.Jit 1.5 runs correctly with (15 aborts, 14 is refused).
MIN_LLVM_MAJOR = 16

SEARCH_DIRS = (
    "/usr/lib/x86_64-linux-gnu", "/usr/lib/aarch64-linux-gnu", "/usr/lib64", "/usr/lib",
    "/usr/local/lib", "/opt/homebrew/opt/llvm/lib", "/usr/local/opt/llvm/lib",
)

FIX = ("install a newer LLVM (Debian/Ubuntu: `apt-get install libllvm19`) or point "
       "DRJIT_LIBLLVM_PATH at a libLLVM.so of version >= %d" % MIN_LLVM_MAJOR)



def llvm_major(path: str) -> int | None:
    """The major version encoded in a libLLVM file name.

    Args:
        path: a file path; only its name is read (libLLVM-19.so, libLLVM.so.19.1,
            libLLVM-15.0.7.so, libLLVM.19.dylib, ...).

    Returns:
        The major version, or None for a name of no such form.
    """
    name = os.path.basename(path)
    m = re.match(r"libLLVM(?:-(\d+)[.\d]*\.(?:so|dylib)|\.so\.(\d+)|\.(\d+)\.dylib)", name)
    if not m:
        return None
    return int(next(g for g in m.groups() if g))


def llvm_major_of_file(path: str) -> int | None:
    """The major version of the libLLVM at `path`, read from the file itself.

    libLLVM exports its symbols under an ELF symbol version `LLVM_<major>[.<minor>]` (in .dynstr),
    so a copy renamed to plain libLLVM.so is still recognised.

    Args:
        path: the library file (an unreadable or empty file falls back to its name).

    Returns:
        The major version from the file, else from its name (`llvm_major`), else None.
    """
    try:
        with open(path, "rb") as fh, mmap.mmap(fh.fileno(), 0, access=mmap.ACCESS_READ) as data:
            at = data.find(b"\0LLVM_")
            while at >= 0:
                m = re.match(rb"\0LLVM_(\d+)(?:\.\d+)*\0", data[at:at + 32])
                if m:
                    return int(m.group(1))
                at = data.find(b"\0LLVM_", at + 1)
    except (OSError, ValueError):  # unreadable, or empty (mmap refuses empty files)
        pass
    return llvm_major(path)


def find_libllvm(dirs=None) -> str | None:
    """Find the newest libLLVM that Dr.Jit runs correctly with, judged by file name.

    Args:
        dirs: folders to search (and their llvm-*/lib subfolders); None: SEARCH_DIRS.

    Returns:
        The path of the libLLVM file of the highest major >= MIN_LLVM_MAJOR, or None.
    """
    best = None
    for d in SEARCH_DIRS if dirs is None else dirs:
        for path in (glob.glob(os.path.join(d, "libLLVM*"))
                     + glob.glob(os.path.join(d, "llvm-*", "lib", "libLLVM*"))):
            major = llvm_major(path)
            if major is None or major < MIN_LLVM_MAJOR or not os.path.isfile(path):
                continue
            if best is None or major > best[0]:
                best = (major, path)
    return best[1] if best else None


def configure_llvm() -> str:
    """Set DRJIT_LIBLLVM_PATH to a working libLLVM (keeping a user's good choice) and return it."""
    user = os.environ.get("DRJIT_LIBLLVM_PATH")
    if user:
        if not os.path.isfile(user):
            raise BackendError(f"DRJIT_LIBLLVM_PATH={user} does not exist; {FIX}")
        major = llvm_major_of_file(user)
        if major is not None and major < MIN_LLVM_MAJOR:
            raise BackendError(f"DRJIT_LIBLLVM_PATH={user} is LLVM {major}, which crashes Dr.Jit "
                               f"1.5; {FIX}")
        return user
    found = find_libllvm()
    if found is None:
        raise BackendError(f"styletrace found no libLLVM >= {MIN_LLVM_MAJOR} for the CPU backend; "
                           f"{FIX}")
    os.environ["DRJIT_LIBLLVM_PATH"] = found
    return found


def cuda_usable() -> bool:
    """True when Dr.Jit can run CUDA kernels here (checked without creating a CUDA context if the
    driver is absent)."""
    if os.environ.get("STYLETRACE_NO_CUDA"):
        return False
    if not any(glob.glob(os.path.join(d, "libcuda.so*")) for d in SEARCH_DIRS):
        return False
    import drjit as dr
    try:
        return bool(dr.has_backend(dr.JitBackend.CUDA))
    except Exception:  # the driver exists but refuses to start: same as no GPU
        return False


def loaded_libllvm() -> str | None:
    """Path of the libLLVM this process has mapped (Linux), or None."""
    try:
        with open("/proc/self/maps") as f:
            for line in f:
                path = line.split()[-1]
                if os.path.basename(path).startswith("libLLVM"):
                    return path
    except OSError:
        pass
    return None


def prepare_drjit() -> str:
    """Point Dr.Jit at a working libLLVM (unless it was imported already) and import it; return the
    backend kernels should use: 'cuda' where CUDA works, else 'llvm'. Needs no Mitsuba."""
    if "drjit" not in sys.modules:  # once imported, Dr.Jit has read DRJIT_LIBLLVM_PATH already
        try:
            configure_llvm()
        except BackendError:
            if not cuda_usable():
                raise
    import drjit as dr
    if cuda_usable():
        return "cuda"
    if not dr.has_backend(dr.JitBackend.LLVM):
        raise BackendError("Dr.Jit could not load libLLVM "
                           f"({os.environ.get('DRJIT_LIBLLVM_PATH')}); {FIX}")
    # Dr.Jit picks its own libLLVM when it was imported before styletrace; refuse one that crashes
    loaded = loaded_libllvm()
    major = llvm_major_of_file(loaded) if loaded else None
    if major is not None and major < MIN_LLVM_MAJOR:
        raise BackendError(
            f"Dr.Jit loaded {loaded} (LLVM {major}), which crashes it; import styletrace before "
            f"drjit/mitsuba, or {FIX}"
        )
    return "llvm"


def check_variant(variant: str) -> str:
    """Refuse variants styles cannot run on: they act on RGB radiance inside JIT-compiled loops.

    Args:
        variant: a Mitsuba variant name.

    Returns:
        `variant`, where it is a JIT variant ending in `_rgb`.

    Raises:
        BackendError: a scalar variant or one that is not RGB.
    """
    if variant.startswith("scalar") or not variant.endswith("_rgb"):
        raise BackendError(
            f"styletrace needs an RGB JIT variant (llvm_ad_rgb or cuda_ad_rgb); the active "
            f"variant is {variant}"
        )
    return variant


def select_variant(requested: str | None = None) -> str:
    """Prepare Dr.Jit (`prepare_drjit`), then set the Mitsuba variant.

    Args:
        requested: the variant to set; None: the one the user already set, else `cuda_ad_rgb`
            where CUDA works and `llvm_ad_rgb` otherwise.

    Returns:
        The active variant.

    Raises:
        BackendError: a variant styles cannot run on or this Mitsuba lacks, a CUDA variant where
            CUDA does not work, or no usable backend.
    """
    if requested is not None:
        check_variant(requested)
    backend = prepare_drjit()
    import mitsuba as mi
    if requested is not None:
        if requested not in mi.variants():
            raise BackendError(f"unknown variant {requested!r}: this Mitsuba has "
                               f"{', '.join(mi.variants())}")
        if requested.startswith("cuda") and backend != "cuda":
            # Mitsuba would fail deep in Dr.Jit's initialisation, with its own traceback
            why = ("STYLETRACE_NO_CUDA is set" if os.environ.get("STYLETRACE_NO_CUDA")
                   else "CUDA does not work here: no NVIDIA GPU or driver")
            raise BackendError(f"cannot use variant {requested!r}: {why}; use llvm_ad_rgb, the "
                               f"CPU backend")
        if mi.variant() != requested:
            try:
                mi.set_variant(requested)
            except ImportError as exc:  # a backend Dr.Jit cannot start: its message, one line
                first = (str(exc).strip().splitlines() or [type(exc).__name__])[0]
                raise BackendError(f"cannot use variant {requested!r}: {first}") from None
        return requested
    current = mi.variant()
    if current:
        return check_variant(current)
    variant = f"{backend}_ad_rgb"
    mi.set_variant(variant)
    return variant


def backend(variant: str | None = None) -> str:
    """Choose libLLVM and the Mitsuba variant once; idempotent and cheap once chosen. Every
    styletrace module that imports Dr.Jit or Mitsuba when it loads calls it first.

    Args:
        variant: a variant to switch to; None keeps the active one (a variant the user set before
            is kept), choosing one where none is set (`select_variant`).

    Returns:
        The active variant.

    Raises:
        BackendError: no usable backend, or a variant styles cannot run on (`check_variant`).
    """
    mi = sys.modules.get("mitsuba")
    if variant is None and mi is not None and mi.variant():
        return check_variant(mi.variant())
    return select_variant(variant)


@contextlib.contextmanager
def no_collection():
    """No automatic cyclic garbage collection inside the block (a context manager).

    The collector's previous state is restored after the block; reference counting still frees
    everything that is not in a cycle at once, and the collector runs at the next allocation after
    the block. Wrap the tracing and launch of a kernel in it: a scene finalised mid-recording makes
    LLVM abort.

    Design: docs/design/collection_during_traces.md.
    """
    was = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was:
            gc.enable()
