"""One import name is installed: ``nbst``. models/ and render/ arrive as nbst.models / nbst.render."""
import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_installed_mapping_from_outside_the_checkout(tmp_path):
    # run from a folder that is not the checkout, so the checkout is not on sys.path
    code = ("import importlib.util as u, nbst, nbst.models, nbst.render, os;"
            "print(os.path.dirname(nbst.models.__file__)); print(os.path.dirname(nbst.render.__file__));"
            "print(u.find_spec('models'), u.find_spec('render'))")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    models_dir, render_dir, tops = r.stdout.splitlines()
    assert Path(models_dir).name in ("models",) and Path(render_dir).name == "render"
    assert tops == "None None"


def test_import_nbst_is_light(tmp_path):
    code = "import sys, nbst; print(sorted(m for m in ('numba', 'mujoco', 'moderngl', 'imageio') if m in sys.modules))"
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "[]"


@pytest.mark.skipif(not (ROOT / "pyproject.toml").is_file(), reason="needs the source checkout")
def test_wheel_holds_only_nbst(tmp_path):
    # the wheel is what `pip install .` installs
    r = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q",
                        "-w", str(tmp_path), str(ROOT)], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    (whl,) = tmp_path.glob("nbst-*.whl")
    names = zipfile.ZipFile(whl).namelist()
    tops = {n.split("/")[0] for n in names}
    assert {t for t in tops if not t.endswith(".dist-info")} == {"nbst"}
    for must in ("nbst/models/__init__.py", "nbst/render/__init__.py", "nbst/problems/diamond-s14.json",
                 "nbst/problems/over5.json", "nbst/problems/diamond-s14-tiny.json", "nbst/sim/kernel.py",
                 "nbst/models/bowling/deck/atlas.json", "nbst/models/bowling/deck/scene.xml", "nbst/py.typed"):
        assert must in names
    # every package of the checkout (models/ and render/ through their links) is in the wheel
    for folder, dirs, files in os.walk(ROOT / "nbst", followlinks=True):
        dirs[:] = [d for d in dirs if d != "__pycache__"]
        if "__init__.py" in files:
            rel = Path(folder).relative_to(ROOT).as_posix()
            assert f"{rel}/__init__.py" in names, f"{rel} is not in the wheel (pyproject's packages)"
    assert not any(n.startswith(("tests/", "benchmarks/", "models/", "render/")) for n in names)


CHECK = ("import importlib.util as u, os, nbst, nbst.models, nbst.render;"
         "print(nbst.__file__); print(nbst.models.__file__); print(nbst.render.__file__);"
         "print(u.find_spec('models'), u.find_spec('render'))")


@pytest.mark.skipif(not (ROOT / "pyproject.toml").is_file(), reason="needs the source checkout")
@pytest.mark.parametrize("editable", [False, True], ids=["pip-install", "pip-install-e"])
def test_pip_install_into_a_fresh_venv(tmp_path, editable):
    # a throwaway venv gets nbst by `pip install .` or `pip install -e .`; imported from outside
    # the checkout it must give nbst.models / nbst.render and no top-level models / render.
    # The dependencies come from this interpreter's site-packages, appended to the venv's path
    # by a plain .pth (so this interpreter's own nbst install, editable or not, is not seen first).
    venv = tmp_path / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=120)
    py = venv / "bin" / "python"
    (site,) = venv.glob("lib/python*/site-packages")
    (site / "zz_outer.pth").write_text("\n".join(p for p in sys.path if p.endswith("-packages")) + "\n")
    cmd = [str(py), "-m", "pip", "install", "-q", "--no-deps", "--no-build-isolation"] + (["-e"] if editable else [])
    r = subprocess.run(cmd + [str(ROOT)], capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert r.returncode == 0, r.stderr[-2000:]
    r = subprocess.run([str(py), "-c", CHECK], capture_output=True, text=True, cwd=tmp_path, timeout=120)
    assert r.returncode == 0, r.stderr
    init, models, render, tops = r.stdout.splitlines()
    assert tops == "None None"
    assert list(venv.glob("lib/python*/site-packages/nbst-*.dist-info")), "nbst not installed in the venv"
    if editable:  # the checkout's folders, through nbst/models and nbst/render (links to models/, render/)
        assert Path(init) == ROOT / "nbst" / "__init__.py"
        assert Path(models).resolve() == ROOT / "models" / "__init__.py"
        assert Path(render).resolve() == ROOT / "render" / "__init__.py"
    else:  # copies inside the venv's site-packages
        for f, sub in ((init, ""), (models, "models"), (render, "render")):
            assert Path(f).is_relative_to(venv) and Path(f).parent == Path(init).parent / sub
