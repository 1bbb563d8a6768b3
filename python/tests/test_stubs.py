"""featherdrive.pyi against the module it describes: every public name of the module and of each
class is in the stubs, and every class, function and member the stubs declare exists (names only;
the signatures are read by type checkers and people)."""
import ast
import pathlib

import featherdrive as fd

STUBS = pathlib.Path(__file__).resolve().parents[1] / "featherdrive.pyi"
# What every exception and enum member carries from Python itself.
INHERITED = set(dir(Exception)) | {"name", "value"}


def read_stubs():
    """Top-level classes (name -> (declared members, base names)), functions and aliases."""
    classes, functions, aliases = {}, set(), set()
    for node in ast.parse(STUBS.read_text()).body:
        if isinstance(node, ast.ClassDef):
            members = set()
            for n in node.body:
                if isinstance(n, ast.FunctionDef):
                    members.add(n.name)
                elif isinstance(n, ast.AnnAssign) and isinstance(n.target, ast.Name):
                    members.add(n.target.id)
                elif isinstance(n, ast.Assign):
                    members.update(t.id for t in n.targets if isinstance(t, ast.Name))
            bases = [b.id for b in node.bases if isinstance(b, ast.Name)]
            classes[node.name] = (members, bases)
        elif isinstance(node, ast.FunctionDef):
            functions.add(node.name)
        elif isinstance(node, (ast.Assign, ast.AnnAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            aliases.update(t.id for t in targets if isinstance(t, ast.Name))
    return classes, functions, aliases


def stub_members(classes, name):
    """A stub class's members with those of its stub bases."""
    members, bases = classes[name]
    out = set(members)
    for b in bases:
        if b in classes:
            out |= stub_members(classes, b)
    return out


def test_every_public_name_of_the_module_is_in_the_stubs():
    classes, functions, aliases = read_stubs()
    public = {n for n in dir(fd) if not n.startswith("_")}
    missing = public - set(classes) - functions - aliases
    assert not missing, f"featherdrive.pyi lacks {sorted(missing)}"


def test_every_class_and_function_of_the_stubs_exists():
    classes, functions, _ = read_stubs()
    absent = sorted(n for n in set(classes) | functions if not hasattr(fd, n))
    assert not absent, f"featherdrive.pyi declares {absent}, which the module does not have"


def test_class_members_agree():
    classes, _, _ = read_stubs()
    differences = []
    for name in sorted(classes):
        if not hasattr(fd, name):
            continue
        declared = stub_members(classes, name)
        actual = {m for m in dir(getattr(fd, name)) if not m.startswith("_")} - INHERITED
        if actual - declared:
            differences.append(f"{name}: not in the stubs {sorted(actual - declared)}")
        undeclared = {m for m in declared if not m.startswith("_")} - INHERITED
        if undeclared - actual:
            differences.append(f"{name}: not in the module {sorted(undeclared - actual)}")
    assert not differences, "; ".join(differences)
