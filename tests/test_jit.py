"""Backend selection: a working libLLVM, never LLVM <= 15, and a clear error without one."""
import os
import subprocess
import sys

import pytest
from conftest import child_env

from styletrace import jit


@pytest.mark.parametrize(
    "name,major",
    [
        ("libLLVM-19.so", 19),
        ("libLLVM.so.19.1", 19),
        ("libLLVM-15.so.1", 15),
        ("libLLVM-14.0.6.so.1", 14),
        ("libLLVM.so.22.1", 22),
        ("libfoo.so", None),
    ],
)
def test_llvm_major(name, major):
    assert jit.llvm_major("/x/" + name) == major


def test_prefers_newest_and_skips_old(tmp_path):
    for name in ("libLLVM-15.so", "libLLVM-19.so", "libLLVM.so.22.1", "libLLVM-14.so"):
        (tmp_path / name).write_bytes(b"")
    assert jit.find_libllvm([str(tmp_path)]).endswith("libLLVM.so.22.1")


def test_only_old_llvm_finds_nothing(tmp_path):
    for name in ("libLLVM-15.so", "libLLVM-14.so"):
        (tmp_path / name).write_bytes(b"")
    assert jit.find_libllvm([str(tmp_path)]) is None


def _import_in_child(env_extra, code="import styletrace; print(styletrace.variant)"):
    env = {
        k: v
        for k, v in child_env(**env_extra).items()
        if k != "DRJIT_LIBLLVM_PATH" or k in env_extra
    }
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120
    )


def test_import_selects_llvm_variant():
    r = _import_in_child({"STYLETRACE_NO_CUDA": "1"})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "llvm_ad_rgb"


def test_user_variant_is_kept():
    r = _import_in_child({"DRJIT_LIBLLVM_PATH": jit.find_libllvm(), "STYLETRACE_NO_CUDA": "1"},
                         "import mitsuba as mi; mi.set_variant('llvm_ad_rgb'); import styletrace; "
                         "print(styletrace.variant, mi.variant())")
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["llvm_ad_rgb", "llvm_ad_rgb"]


@pytest.mark.parametrize("variant", ["llvm_ad_mono", "llvm_ad_spectral", "scalar_rgb"])
def test_a_user_variant_styles_cannot_run_on_is_a_clear_error(variant):
    """Not silently replaced, not an obscure failure at render time: one error naming the
    variant."""
    r = _import_in_child(
        {"DRJIT_LIBLLVM_PATH": jit.find_libllvm()},
        f"import mitsuba as mi; mi.set_variant('{variant}'); import styletrace; styletrace.init()",
    )
    assert r.returncode != 0
    assert (
        f"styletrace needs an RGB JIT variant (llvm_ad_rgb or cuda_ad_rgb); the active variant is "
        f"{variant}" in r.stderr
    )


def test_llvm15_is_refused_with_a_clear_error(tmp_path):
    fake = tmp_path / "libLLVM-15.so"
    fake.write_bytes(b"")
    r = _import_in_child({"DRJIT_LIBLLVM_PATH": str(fake), "STYLETRACE_NO_CUDA": "1"})
    assert r.returncode != 0
    assert "apt-get install libllvm19" in r.stderr and "DRJIT_LIBLLVM_PATH" in r.stderr


def test_no_llvm_at_all_is_a_clear_error(monkeypatch):
    monkeypatch.delenv("DRJIT_LIBLLVM_PATH", raising=False)
    monkeypatch.setattr(jit, "SEARCH_DIRS", ())
    with pytest.raises(jit.BackendError, match=r"apt-get install libllvm19.*DRJIT_LIBLLVM_PATH"):
        jit.configure_llvm()


def test_the_loaded_llvm_is_new_enough():
    import styletrace  # noqa: F401
    loaded = jit.loaded_libllvm()
    assert loaded is not None and jit.llvm_major(loaded) >= jit.MIN_LLVM_MAJOR


def test_a_chosen_variant_wins_over_cuda(monkeypatch):
    """Even where CUDA would be usable, a variant the user already set is kept."""
    import mitsuba as mi
    monkeypatch.setattr(jit, "cuda_usable", lambda: True)
    assert jit.select_variant() == "llvm_ad_rgb" and mi.variant() == "llvm_ad_rgb"


def test_a_cuda_variant_without_cuda_is_one_backend_error(monkeypatch):
    """`styletrace.init("cuda_ad_rgb")` where CUDA does not work: the documented BackendError in
    one line (not Dr.Jit's traceback from `mi.set_variant`), and the active variant stays."""
    import mitsuba as mi

    import styletrace
    before = styletrace.init()
    monkeypatch.setattr(jit, "cuda_usable", lambda: False)
    monkeypatch.delenv("STYLETRACE_NO_CUDA", raising=False)
    with pytest.raises(styletrace.BackendError) as info:
        styletrace.init("cuda_ad_rgb")
    assert str(info.value) == ("cannot use variant 'cuda_ad_rgb': CUDA does not work here: no "
                               "NVIDIA GPU or driver; use llvm_ad_rgb, the CPU backend")
    assert mi.variant() == before


def test_a_cuda_variant_with_cuda_switched_off_names_the_switch():
    r = _import_in_child(
        {"STYLETRACE_NO_CUDA": "1"},
        "import styletrace\ntry:\n    styletrace.init('cuda_ad_rgb')\n"
        "except styletrace.BackendError as exc:\n    print(exc)\nprint(styletrace.init())",
    )
    assert r.returncode == 0, r.stderr
    assert r.stdout.splitlines() == [
        "cannot use variant 'cuda_ad_rgb': STYLETRACE_NO_CUDA is set; use llvm_ad_rgb, the CPU "
        "backend", "llvm_ad_rgb"]


def test_command_without_llvm_is_one_line_and_exit_2(tmp_path):
    """The command line turns a backend failure (no usable libLLVM) into its one-line error."""
    fake = tmp_path / "libLLVM-15.so"
    fake.write_bytes(b"")
    r = _import_in_child(
        {"DRJIT_LIBLLVM_PATH": str(fake), "STYLETRACE_NO_CUDA": "1"},
        "import sys; from styletrace.frontends.cli import main; sys.exit(main(['render']))",
    )
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert (
        len(lines) == 1
        and lines[0].startswith("styletrace: error: ")
        and "apt-get install libllvm19" in lines[0]
    )


LIBDIR = "/usr/lib/x86_64-linux-gnu"


@pytest.mark.skipif(
    not os.path.exists(f"{LIBDIR}/libLLVM-15.so.1"), reason="needs the system's libLLVM 15"
)
def test_an_unversioned_libllvm_15_is_refused_by_its_contents(tmp_path):
    """A copy of libLLVM 15 named plain libLLVM.so: its ELF symbol version LLVM_15 gives it away,
    so the process ends with the one-line error instead of Dr.Jit aborting it (status 134)."""
    copy = tmp_path / "libLLVM.so"
    copy.write_bytes(open(f"{LIBDIR}/libLLVM-15.so.1", "rb").read())
    assert jit.llvm_major(str(copy)) is None and jit.llvm_major_of_file(str(copy)) == 15
    r = _import_in_child({"STYLETRACE_NO_CUDA": "1", "DRJIT_LIBLLVM_PATH": str(copy)})
    assert r.returncode == 1, (r.returncode, r.stderr)
    assert (
        f"BackendError: DRJIT_LIBLLVM_PATH={copy} is LLVM 15, which crashes Dr.Jit 1.5" in r.stderr
    )


@pytest.mark.skipif(
    not os.path.exists(f"{LIBDIR}/libLLVM.so.19.1"), reason="needs the system's libLLVM 19"
)
def test_an_unversioned_libllvm_19_is_accepted(tmp_path):
    copy = tmp_path / "libLLVM.so"
    copy.write_bytes(open(f"{LIBDIR}/libLLVM.so.19.1", "rb").read())
    assert jit.llvm_major_of_file(str(copy)) == 19
    r = _import_in_child({"STYLETRACE_NO_CUDA": "1", "DRJIT_LIBLLVM_PATH": str(copy)})
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "llvm_ad_rgb"


def test_a_file_without_a_version_marker_falls_back_to_its_name(tmp_path):
    for name, major in (("libLLVM-15.so", 15), ("libLLVM.so", None)):
        (tmp_path / name).write_bytes(b"\0not an ELF file\0")
        assert jit.llvm_major_of_file(str(tmp_path / name)) == major
