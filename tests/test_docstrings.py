"""Every public function, class and method of ``identification/`` and ``vrig/`` is documented in
numpydoc style (issue 14, acceptance: "every public function and method documented (a numpydoc
docstring test like python-control's)").

Public: a name without a leading underscore, in a module whose path has no component with one
(``__init__.py`` counts as public), methods and properties of public classes included, dunder
methods not (a class documents its constructor).

Checked, for every public definition:

- it has a non-empty docstring;
- a function or method that takes parameters (``self``/``cls`` aside) has a numpydoc
  ``Parameters`` (or ``Other Parameters``) section that names every parameter of its signature
  and no name the signature does not have, each with a description; ``*args``/``**kwargs``
  are documented under their name with or without the stars (``**method_options``); a line
  ``a, b : float`` documents both ``a`` and ``b``;
- a class's constructor parameters are documented in the class docstring: the ``Parameters``
  of an explicit ``__init__`` (in the class docstring or in ``__init__``'s own), the fields of
  a ``@dataclass`` under ``Parameters`` or ``Attributes``. Properties (and their setters) need
  only their one-line docstring.

As python-control's ``control/tests/docstrings_test.py`` checks every documented argument against
``inspect.signature``, this test checks them against the signature in the source, read with
:mod:`ast` and never imported: importing ``vrig`` pulls MuJoCo, numba compilation and gymnasium
registration into a documentation test, the numba-jitted and ``@intrinsic`` functions hide their
Python signature behind a dispatcher, and a module that fails to import would hide all of its
definitions; the source is the one thing every definition has. Sections are parsed by
``numpydoc.docscrape`` (the parser numpydoc's Sphinx extension uses).
"""

from __future__ import annotations

import ast
import warnings
from pathlib import Path

from numpydoc import docscrape  # the test extra: pip install -e ".[test]"

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("identification", "vrig")

# Decorators whose function is not called with the signature it is written with.
PROPERTY_DECORATORS = ("property", "cached_property", "setter", "deleter", "getter")
# ... and those that wrap a core in a public signature: the core's docstring documents that one
# (``identification.solvers._solver``: a core ``(Xs, Y, tol, norms)`` is called ``(X, Y, rcond=)``).
SIGNATURE_SET_BY_DECORATOR = {"_solver": ["X", "Y", "rcond"]}


def _is_public_module(rel: Path) -> bool:
    return not any(p.startswith("_") and p not in ("__init__.py", "__main__.py") for p in rel.parts)


def _decorator_names(node: ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef) -> list[str]:
    """The last dotted component of every decorator (``dataclass`` for ``@dataclass(frozen=True)``,
    ``setter`` for ``@x.setter``)."""
    names = []
    for deco in node.decorator_list:
        target = deco.func if isinstance(deco, ast.Call) else deco
        if isinstance(target, ast.Attribute):
            names.append(target.attr)
        elif isinstance(target, ast.Name):
            names.append(target.id)
    return names


def signature_names(func: ast.FunctionDef | ast.AsyncFunctionDef, in_class: bool) -> list[str]:
    """The parameter names of ``func`` in signature order, without ``self``/``cls`` (the first
    positional parameter of a method that is not a ``@staticmethod``); ``*args`` and ``**kwargs``
    as ``args`` and ``kwargs``; a decorator of ``SIGNATURE_SET_BY_DECORATOR`` sets them."""
    for deco in _decorator_names(func):
        if deco in SIGNATURE_SET_BY_DECORATOR:
            return list(SIGNATURE_SET_BY_DECORATOR[deco])
    a = func.args
    positional = [p.arg for p in (*a.posonlyargs, *a.args)]
    if in_class and "staticmethod" not in _decorator_names(func) and positional:
        positional = positional[1:]
    names = positional + [p.arg for p in a.kwonlyargs]
    names += [p.arg for p in (a.vararg, a.kwarg) if p is not None]
    return names


def _is_classvar_or_initfalse(stmt: ast.AnnAssign) -> bool:
    if "ClassVar" in ast.unparse(stmt.annotation):
        return True
    value = stmt.value
    if isinstance(value, ast.Call) and ast.unparse(value.func).split(".")[-1] == "field":
        for kw in value.keywords:
            if kw.arg == "init" and isinstance(kw.value, ast.Constant) and kw.value.value is False:
                return True
    return False


def dataclass_fields(cls: ast.ClassDef) -> list[str]:
    """The ``__init__`` fields a ``@dataclass`` declares in its own body (``ClassVar`` and
    ``field(init=False)`` excluded; inherited fields are documented by the base class)."""
    return [
        stmt.target.id
        for stmt in cls.body
        if isinstance(stmt, ast.AnnAssign)
        and isinstance(stmt.target, ast.Name)
        and not _is_classvar_or_initfalse(stmt)
    ]


def documented_names(doc: str, sections: tuple[str, ...]) -> tuple[dict[str, str], list[str]]:
    """``(name -> description, problems)`` for the entries of the numpydoc ``sections`` of
    ``doc``: ``a, b : float`` gives ``a`` and ``b``; stars are stripped (``**kwargs`` ->
    ``kwargs``). ``problems`` holds the parser's complaints (an unknown or repeated section)."""
    problems: list[str] = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            parsed = docscrape.NumpyDocString(doc)
        except ValueError as exc:  # a repeated section
            return {}, [str(exc)]
    problems += [str(w.message) for w in caught]
    names: dict[str, str] = {}
    for section in sections:
        for entry in parsed[section]:
            text = " ".join(line.strip() for line in entry.desc).strip()
            for part in entry.name.split(","):
                part = part.strip().lstrip("*")
                if part:
                    names[part] = text
    return names, problems


def _check_entries(
    doc: str, wanted: list[str], sections: tuple[str, ...], extra_ok: bool = False
) -> list[str]:
    names, problems = documented_names(doc, sections)
    problems += [f"parameter {n!r} not documented" for n in wanted if n not in names]
    if not extra_ok:
        problems += [f"documents {n!r}, which is not a parameter" for n in names if n not in wanted]
    problems += [f"{n!r} has no description" for n in wanted if names.get(n) == ""]
    return problems


def docstring_problems(source: str) -> dict[str, list[str]]:
    """Qualified name -> list of problems (empty when fine), for every public function, class
    and method (of a public class, at any nesting of classes) in ``source``."""
    found: dict[str, list[str]] = {}

    def check_function(node: ast.FunctionDef | ast.AsyncFunctionDef, in_class: bool) -> list[str]:
        doc = ast.get_docstring(node)
        if not (doc and doc.strip()):
            return ["no docstring"]
        if in_class and set(_decorator_names(node)) & set(PROPERTY_DECORATORS):
            return []
        wanted = signature_names(node, in_class)
        if not wanted:
            return []
        return _check_entries(doc, wanted, ("Parameters", "Other Parameters"))

    def check_class(node: ast.ClassDef) -> list[str]:
        doc = ast.get_docstring(node)
        if not (doc and doc.strip()):
            return ["no docstring"]
        init = next(
            (s for s in node.body if isinstance(s, ast.FunctionDef) and s.name == "__init__"),
            None,
        )
        if init is not None:
            wanted = signature_names(init, in_class=True)
            if not wanted:
                return []
            init_doc = ast.get_docstring(init) or ""
            return _check_entries(
                doc + "\n\n" + init_doc if "Parameters\n" in init_doc else doc,
                wanted,
                ("Parameters", "Other Parameters"),
            )
        if "dataclass" in _decorator_names(node):
            wanted = dataclass_fields(node)
            problems = _check_entries(doc, wanted, ("Parameters", "Attributes"), extra_ok=True)
            params, _ = documented_names(doc, ("Parameters",))
            problems += [f"documents {n!r}, which is not a field" for n in params if n not in wanted]
            return problems
        return []

    def visit(body: list[ast.stmt], prefix: str) -> None:
        for node in body:
            if not isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                continue
            if node.name.startswith("_"):
                continue
            name = prefix + node.name
            if isinstance(node, ast.ClassDef):
                found[name] = check_class(node)
                visit(node.body, name + ".")
            elif name not in found or found[name]:  # a property's setter after its getter
                found[name] = check_function(node, in_class=bool(prefix))

    visit(ast.parse(source).body, "")
    return found


def _package_problems() -> dict[tuple[str, str], list[str]]:
    found = {}
    for top in PACKAGES:
        for path in sorted((ROOT / top).rglob("*.py")):
            rel = path.relative_to(ROOT)
            if "__pycache__" in rel.parts or not _is_public_module(rel):
                continue
            for name, problems in docstring_problems(path.read_text(encoding="utf-8")).items():
                found[rel.as_posix(), name] = problems
    return found


# -- the checker, on hand-written sources (each case one the old presence-only test let pass) ---


def _problems(src: str) -> dict[str, list[str]]:
    return {k: v for k, v in docstring_problems(src).items() if v}


def test_public_definitions_are_found_and_private_ones_skipped():
    src = (
        'def f():\n    """Doc."""\n\ndef g():\n    pass\n\ndef _h():\n    pass\n\n'
        "class C:\n    def __init__(self):\n        pass\n\n    @property\n"
        "    def p(self):\n        return 1\n\n    def _q(self):\n        pass\n\n"
        '    class D:\n        """ """\n'
    )
    expected = {"f": [], "g": ["no docstring"], "C": ["no docstring"], "C.p": ["no docstring"]}
    expected["C.D"] = ["no docstring"]
    assert docstring_problems(src) == expected
    assert _is_public_module(Path("vrig/io/__init__.py"))
    assert not _is_public_module(Path("identification/_sensitivity.py"))


GOOD = '''
def f(a, b, c=1, *rest, d, **options):
    """Do it.

    Parameters
    ----------
    a, b : float
        Two numbers, in m.
    c : int, optional
        A count.
    *rest : float
        More numbers.
    d : str
        A name.
    **options
        Passed on to ``g``.
    """


class C:
    """A thing.

    Parameters
    ----------
    x : float
        Position, in m.
    """

    def __init__(self, x):
        self.x = x

    @staticmethod
    def s(y):
        """Static.

        Parameters
        ----------
        y : float
            Anything.
        """

    @classmethod
    def k(cls):
        """No parameter but ``cls``."""

    @property
    def p(self):
        """A property needs one line."""

    @p.setter
    def p(self, value):
        self.x = value
'''


def test_a_complete_numpydoc_docstring_passes():
    assert _problems(GOOD) == {}


def test_a_parameter_missing_from_the_docstring_is_found():
    src = GOOD.replace("    c : int, optional\n        A count.\n", "")
    assert _problems(src) == {"f": ["parameter 'c' not documented"]}


def test_a_function_with_parameters_but_no_parameters_section_is_found():
    src = 'def f(x):\n    """Only a summary."""\n'
    assert _problems(src) == {"f": ["parameter 'x' not documented"]}


def test_a_documented_name_the_signature_does_not_have_is_found():
    src = GOOD.replace("d : str", "e : str")
    assert _problems(src) == {
        "f": ["parameter 'd' not documented", "documents 'e', which is not a parameter"]
    }


def test_a_parameter_without_a_description_is_found():
    src = 'def f(x):\n    """Do.\n\n    Parameters\n    ----------\n    x : float\n    """\n'
    assert _problems(src) == {"f": ["'x' has no description"]}


def test_self_cls_and_staticmethods_are_handled():
    src = GOOD.replace("        y : float\n            Anything.\n", "")
    assert _problems(src) == {"C.s": ["parameter 'y' not documented"]}


def test_constructor_parameters_are_checked_in_the_class_docstring_or_init():
    no_class_params = GOOD.replace("    Parameters\n    ----------\n    x : float\n", "", 1)
    no_class_params = no_class_params.replace("        Position, in m.\n", "", 1)
    assert _problems(no_class_params) == {"C": ["parameter 'x' not documented"]}
    in_init = no_class_params.replace(
        "        self.x = x\n",
        '        """Make it.\n\n        Parameters\n        ----------\n        x : float\n'
        '            Position, in m.\n        """\n        self.x = x\n',
    )
    assert _problems(in_init) == {}


def test_dataclass_fields_are_checked_under_parameters_or_attributes():
    src = (
        "@dataclass(frozen=True)\nclass D:\n"
        '    """Data.\n\n    Attributes\n    ----------\n    a : float\n        In s.\n    """\n\n'
        "    a: float\n    b: int = 0\n    c: ClassVar[int] = 1\n"
        "    d: list = field(default_factory=list, init=False)\n"
    )
    assert _problems(src) == {"D": ["parameter 'b' not documented"]}
    src = src.replace("Attributes\n    ----------\n", "Parameters\n    ----------\n")
    src = src.replace("    a : float\n", "    a, b, z : float\n")
    assert _problems(src) == {"D": ["documents 'z', which is not a field"]}


# -- the packages -----------------------------------------------------------------------------


def test_every_public_function_and_method_is_documented_in_numpydoc():
    found = _package_problems()
    assert len(found) > 300, "too few public definitions found: wrong root?"
    bad = sorted((key, problems) for key, problems in found.items() if problems)
    assert not bad, f"{len(bad)} public definitions not documented in numpydoc style:\n" + "\n".join(
        f"{f}:{name}: {'; '.join(problems)}" for (f, name), problems in bad
    )

