#!/usr/bin/env python3
"""The Python modules the guest's tools import (hil/xcp_master.py: python-can and pyxcp; hil/uds_tester.py:
python-can, python-can-isotp and udsoncan) in one tar, for the emulated guest's own tmpfs (hil/guest_lib.sh,
guest_python): run on the host by scripts/setup.sh.

    python hil/guest_pylib.py OUT.tar

Why: the guest reads the host's file system over 9p, and under emulation every file-system call is an exit
to QEMU: the imports of python-can and pyxcp took 58-64 s of the guest's time on a loaded 2-core machine,
38-44 s of it system time (the import system's stat, open and read of some 500 modules and their
directories). From the tmpfs copy (read once a boot, as one file) they are found without 9p. The copy
holds the same files (every module imported, the standard library's among them, and every package one
of them is in, whole) with their bytecode, compiled here
with the sources' times kept, so Python uses it as it is; a module the tools import later than at start-up
and the copy lacks is found where it always was (the copy is the first entry of PYTHONPATH, nothing is
taken off the path)."""
from __future__ import annotations

import compileall
import os
import shutil
import sys
import tarfile
import tempfile
from pathlib import Path

# python-can's MF4 writer imports asammdf, pyxcp's recorder pandas: the tools keep both out (hil/xcp_master.py)
sys.modules.setdefault("asammdf", None)
sys.modules.setdefault("pandas", None)



def _import_all() -> None:
    import can  # noqa: F401
    import can.interfaces.socketcan  # noqa: F401
    import isotp  # noqa: F401
    import udsoncan  # noqa: F401
    from pyxcp.config import create_application_from_config, set_application  # noqa: F401
    from pyxcp.daq_stim import DaqList, DaqOnlinePolicy  # noqa: F401
    from pyxcp.master import Master  # noqa: F401
    from pyxcp.types import XcpResponseError  # noqa: F401
    from udsoncan import exceptions  # noqa: F401
    from udsoncan.client import Client  # noqa: F401
    from udsoncan.connections import PythonIsoTpConnection  # noqa: F401


def _roots() -> list[Path]:
    """The directories the modules are copied from, each to the copy's top (the site-packages first)."""
    roots = [Path(p) for p in sys.path[1:] if p]   # not this script's directory
    return sorted({r.resolve() for r in roots if r.is_dir()}, key=lambda r: -len(r.parts))


def files() -> set[tuple[Path, Path]]:
    """(source file, its path in the copy) of every module imported: the whole package of a submodule."""
    _import_all()
    roots = _roots()
    out: set[tuple[Path, Path]] = set()
    for module in list(sys.modules.values()):
        f = getattr(module, "__file__", None)
        if not f or not f.endswith((".py", ".so")):
            continue
        path = Path(f).resolve()
        root = next((r for r in roots if r in path.parents), None)
        if root is None or path.name.startswith("__editable__"):
            continue
        rel = path.relative_to(root)
        if len(rel.parts) == 1:   # a module of its own
            out.add((path, rel))
            continue
        # a package: whole (a submodule imported later, only on an error's path perhaps, must be in the copy,
        # which hides the original directory from the package; a data file it reads too)
        for file in (root / rel.parts[0]).rglob("*"):
            if file.is_file() and "__pycache__" not in file.parts and not file.name.endswith(".pyc"):
                out.add((file, file.relative_to(root)))
    return out


def main() -> int:
    if len(sys.argv) != 2:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    out = Path(sys.argv[1])
    with tempfile.TemporaryDirectory() as tmp:
        stage = Path(tmp) / "pylib"
        for source, rel in sorted(files()):
            (stage / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source, stage / rel)   # the source's time: the bytecode below is valid for it
        compileall.compile_dir(stage, quiet=2, workers=1)
        part = out.with_name(out.name + ".part")
        with tarfile.open(part, "w") as tar:
            tar.add(stage, arcname=".")
        os.replace(part, out)
    print(f"guest_pylib: {out} ({out.stat().st_size >> 20} MB)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
