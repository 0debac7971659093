"""Builds the Rust library with cargo and ships it inside the package.

`pip install ./python` (from the repository root) runs `cargo build --release
--lib` in the repository this folder belongs to and copies the shared library
into the `plumage` package. CARGO_TARGET_DIR is honoured; PLUMAGE_CARGO names
another cargo binary.
"""

import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import Distribution, setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
REPO = HERE.parent


def library_file_name() -> str:
    if sys.platform == "darwin":
        return "libplumage.dylib"
    if sys.platform == "win32":
        return "plumage.dll"
    return "libplumage.so"


class BuildWithCargo(build_py):
    def run(self) -> None:
        super().run()
        if not (REPO / "Cargo.toml").is_file():
            raise RuntimeError(f"no Cargo.toml in {REPO}: install the package from the Plumage repository")
        cargo = os.environ.get("PLUMAGE_CARGO") or shutil.which("cargo") or str(Path.home() / ".cargo" / "bin" / "cargo")
        subprocess.run([cargo, "build", "--release", "--lib"], cwd=REPO, check=True)
        target = Path(os.environ.get("CARGO_TARGET_DIR") or REPO / "target")
        if not target.is_absolute():
            target = REPO / target
        built = target / "release" / library_file_name()
        if not built.is_file():
            raise RuntimeError(f"cargo did not produce {built}")
        out_dir = Path(self.build_lib) / "plumage"
        out_dir.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, out_dir / library_file_name())


class BinaryDistribution(Distribution):
    """The wheel carries a native library: platform-specific, not pure."""

    def has_ext_modules(self) -> bool:
        return True


setup(cmdclass={"build_py": BuildWithCargo}, distclass=BinaryDistribution)
