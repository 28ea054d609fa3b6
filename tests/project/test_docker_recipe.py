"""The Debian image (docker/) covers what the code imports, at the versions it runs on.

docker/packages.txt lists Debian packages as ``NAME [VERSION-GLOB]``. These tests
catch drift between that list and the code: a third-party import with no Debian
package, a pinned series that differs from the Python stack the suite runs on
(the PyPI wheel locally, Debian's packages in the image), and use of the wheel's
``dolfinx_solver`` outside its guarded import.
"""

import ast
import fnmatch
import importlib
import re
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CODE_DIRS = ("common", "solver", "geometry", "demos", "tests", "benchmarks")
WHEEL_ONLY = "dolfinx_solver"  # PyPI wheel only; imported in common/backend.py alone

# Import name -> Debian package that provides it, where not python3-<name>.
# basix, ufl and ffcx come with python3-dolfinx-real (it depends on them).
DEBIAN_PACKAGE_OF = {
    "petsc4py": "python3-petsc4py-real",
    "slepc4py": "python3-slepc4py-real",
    "basix": "python3-dolfinx-real",
    "ufl": "python3-dolfinx-real",
    "ffcx": "python3-dolfinx-real",
}
# Pinned Debian package -> Python module whose __version__ must be in its series.
PINNED_MODULE_OF = {
    "python3-dolfinx-real": "dolfinx",
    "python3-petsc4py-real": "petsc4py",
    "python3-slepc4py-real": "slepc4py",
    "python3-gmsh": "gmsh",
}


def parse_package_list(text: str, source: str) -> dict[str, str | None]:
    """Package name -> version glob (None if unpinned) of packages.txt text."""
    packages: dict[str, str | None] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        fields = line.split("#", 1)[0].split()
        if not fields:
            continue
        if len(fields) > 2 or not re.fullmatch(r"[a-z0-9][a-z0-9.+-]+", fields[0]):
            raise ValueError(f"{source}:{number}: expected 'NAME [VERSION-GLOB]', got {line!r}")
        if fields[0] in packages:
            raise ValueError(f"{source}:{number}: {fields[0]} listed twice")
        packages[fields[0]] = fields[1] if len(fields) == 2 else None
    return packages


def upstream_glob(debian_glob: str) -> str:
    """The upstream part of a Debian version glob: no epoch, no Debian revision."""
    return debian_glob.split(":", 1)[-1].rsplit("-", 1)[0]


def top_level_imports(path: Path) -> set[str]:
    """Top-level module names imported (absolutely) by a Python file."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def python_files() -> list[Path]:
    return sorted(f for d in CODE_DIRS for f in (ROOT / d).rglob("*.py"))


@pytest.fixture(scope="module")
def packages() -> dict[str, str | None]:
    return parse_package_list((ROOT / "docker" / "packages.txt").read_text(), "packages.txt")


def test_package_list_rejects_malformed_lines():
    with pytest.raises(ValueError, match="bad.txt:2"):
        parse_package_list("python3-numpy\npython3-gmsh 4.15.* extra\n", "bad.txt")
    with pytest.raises(ValueError, match="listed twice"):
        parse_package_list("python3-numpy\npython3-numpy\n", "bad.txt")


def test_upstream_glob_strips_epoch_and_revision():
    assert upstream_glob("1:0.11.0.post0-*") == "0.11.0.post0"
    assert upstream_glob("3.25.*") == "3.25.*"


def test_every_third_party_import_has_a_debian_package(packages):
    # the project's packages and the helper modules beside the scripts and tests
    local = set(CODE_DIRS) | {path.stem for path in python_files()}
    missing = {}
    for path in python_files():
        for name in top_level_imports(path) - local - {WHEEL_ONLY}:
            if name in sys.stdlib_module_names:
                continue
            package = DEBIAN_PACKAGE_OF.get(name, f"python3-{name}")
            if package not in packages:
                missing.setdefault(f"{name} ({package})", []).append(str(path.relative_to(ROOT)))
    assert not missing, f"imports without a package in docker/packages.txt: {missing}"


def test_pinned_series_match_the_running_stack(packages):
    for package, module_name in PINNED_MODULE_OF.items():
        glob = packages.get(package)
        assert glob is not None, f"{package} must be pinned in docker/packages.txt"
        version = importlib.import_module(module_name).__version__
        assert fnmatch.fnmatchcase(version, upstream_glob(glob)), (
            f"{module_name} {version} is outside docker/packages.txt's {package} {glob}"
        )


def test_wheel_module_is_imported_only_by_the_backend():
    users = [
        str(path.relative_to(ROOT))
        for path in python_files()
        if WHEEL_ONLY in top_level_imports(path)
    ]
    assert users == ["common/backend.py"]


def test_dockerfile_default_command_runs_an_existing_demo():
    text = (ROOT / "docker" / "Dockerfile").read_text()
    command = re.search(r"^CMD \[(.*)\]$", text, re.MULTILINE)
    assert command is not None, "docker/Dockerfile has no exec-form CMD"
    words = [w.strip().strip('"') for w in command.group(1).split(",")]
    assert words[:3] == ["mpirun", "-n", "2"]
    assert (ROOT / words[4]).is_file(), f"CMD runs {words[4]}, which does not exist"
    for variable in ("OMPI_ALLOW_RUN_AS_ROOT=1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1"):
        assert re.search(rf"^ENV {variable}$", text, re.MULTILINE), (
            f"Dockerfile lacks ENV {variable}"
        )


def test_the_project_is_installed_the_same_way_everywhere():
    """The image, its debootstrap check and scripts/setup_env.sh (.venv) install the project
    editable without dependencies."""
    for path in ("docker/Dockerfile", "docker/check_debootstrap.sh", "scripts/setup_env.sh"):
        text = (ROOT / path).read_text()
        assert re.search(r"pip install [^\n]*--no-deps[^\n]*-e \.", text), (
            f"{path} does not install the project"
        )


def test_the_installed_packages_are_every_package_folder():
    """pyproject.toml's package discovery includes every folder with an __init__.py, and the
    code reaches the packages through the installation, never through sys.path edits."""
    import tomllib

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())
    include = config["tool"]["setuptools"]["packages"]["find"]["include"]
    folders = {
        path.parent.relative_to(ROOT).as_posix().replace("/", ".")
        for path in ROOT.glob("*/**/__init__.py")
        if ".venv" not in path.parts
    }
    missing = [
        name
        for name in folders
        if not any(fnmatch.fnmatchcase(name, pattern) for pattern in include)
    ]
    assert not missing, f"packages not installed by pyproject.toml: {missing}"
    editing = [
        str(path.relative_to(ROOT))
        for path in python_files()
        if path.name != "test_docker_recipe.py" and "sys.path" in path.read_text()
    ]
    assert not editing, f"sys.path edited in {editing}"


def test_no_script_hides_a_package():
    """A script's folder comes first on sys.path, so a demo or benchmark named like one of the
    project's packages would hide it."""
    packages = {path.parent.name for path in ROOT.glob("*/__init__.py")}
    clashes = [
        str(path.relative_to(ROOT))
        for d in ("demos", "benchmarks")
        for path in (ROOT / d).glob("*.py")
        if path.stem in packages
    ]
    assert not clashes, f"scripts named like a package: {clashes}"
