"""`cmake --install` puts a package that a fresh shell imports: no PYTHONPATH, no build tree.
The prefix stands in for /usr/local, whose site folder Debian's python3 searches by itself."""
import subprocess
import sys

from conftest import BIN, run


def test_a_fresh_shell_imports_the_installed_package(tmp_path):
    prefix = tmp_path / "prefix"
    run(["cmake", "--install", str(BIN.parent), "--prefix", str(prefix)])
    packages = list(prefix.glob("lib/python3*/*-packages/cwloc/__init__.py"))
    assert len(packages) == 1, list(prefix.rglob("cwloc"))
    done = subprocess.run(
        [sys.executable, "-c", "import cwloc; print(cwloc.__version__, cwloc.__file__)"],
        env={"PATH": "/usr/bin:/bin", "PYTHONPATH": str(packages[0].parent.parent)},
        cwd=tmp_path, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    version, path = done.stdout.split()
    out, _ = run([str(prefix / "bin" / "cwloc-localize"), "--version"])
    assert version == out.split()[-1]
    assert path.startswith(str(prefix))  # not the build tree's package
