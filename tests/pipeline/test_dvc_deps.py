"""dvc.yaml names, for each stage, exactly the source files the stage imports (pipeline/deps.py)."""

import yaml

from pipeline.deps import ROOT, project_files

DVC = yaml.safe_load((ROOT / "dvc.yaml").read_text(encoding="utf-8"))


def code_deps(stage: dict) -> set[str]:
    deps = [next(iter(d)) if isinstance(d, dict) else d for d in stage.get("deps", [])]
    return {d for d in deps if d.split("/")[0] in ("bogie", "pipeline")}


def test_every_stage_lists_exactly_the_project_files_it_imports():
    for name, stage in DVC["stages"].items():
        module = stage["cmd"].removeprefix("python -m ")
        imported = {p.relative_to(ROOT).as_posix() for p in project_files(module)}
        declared = code_deps(stage)
        if name == "report":  # it prints the hash of all the code (pipeline.report.inputs.code_digest)
            assert declared == {"bogie", "pipeline"}
            continue
        missing, extra = sorted(imported - declared), sorted(declared - imported)
        assert declared == imported, f"{name}: missing {missing}, extra {extra}"


def test_the_simulation_does_not_depend_on_the_cli_plotting_or_report():
    files = {p.relative_to(ROOT).as_posix() for p in project_files("pipeline.simulate")}
    assert {
        "bogie/steel/nonlinear.py",
        "bogie/steel/force/core.py",
        "bogie/fleet/weighing/protocols.py",
        "pipeline/schema.py",
    } <= files
    assert not files & {
        "bogie/cli.py",
        "bogie/plotting.py",
        "bogie/steel/fe/__init__.py",
        "pipeline/report/__init__.py",
    }


def test_the_import_graph_follows_imports_inside_functions_and_relative_ones(tmp_path):
    (tmp_path / "pipeline").mkdir()
    (tmp_path / "bogie").mkdir()
    for package in ("pipeline", "bogie"):
        (tmp_path / package / "__init__.py").write_text("")
    (tmp_path / "pipeline" / "a.py").write_text("def f():\n    from pipeline import b\n")
    (tmp_path / "pipeline" / "b.py").write_text("from .c import x\nimport numpy\n")
    (tmp_path / "pipeline" / "c.py").write_text("from bogie.d import y\n")
    (tmp_path / "bogie" / "d.py").write_text("")
    (tmp_path / "bogie" / "unused.py").write_text("")
    found = {p.relative_to(tmp_path).as_posix() for p in project_files("pipeline.a", root=tmp_path)}
    assert found == {"pipeline/__init__.py", "pipeline/a.py", "pipeline/b.py", "pipeline/c.py", "bogie/__init__.py",
                     "bogie/d.py"}  # fmt: skip


def test_no_stage_imports_a_name_through_a_package_that_loads_it_lazily():
    """The import graph sees ``from bogie.fleet.calibration import calibrate`` as the package's light __init__ only
    (bogie.lazy): the stage's dvc.yaml deps and code hash would miss the module that defines the name. Every name the
    pipeline imports from a lazy package must be a submodule of it."""
    import ast

    from pipeline.deps import module_file

    wrong = []
    for path in sorted((ROOT / "pipeline").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if not isinstance(node, ast.ImportFrom) or not (node.module or "").startswith("bogie"):
                continue
            init = module_file(node.module)
            if init is None or init.name != "__init__.py" or "lazy_names" not in init.read_text(encoding="utf-8"):
                continue
            for alias in node.names:
                if module_file(f"{node.module}.{alias.name}") is None:
                    wrong.append(f"{path.relative_to(ROOT)}: from {node.module} import {alias.name}")
    assert not wrong, wrong
