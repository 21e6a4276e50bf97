"""Writes the type stubs (__init__.pyi) of the compiled quadrix extension from its own signatures.

Run at build time by Debian's python3 on the freshly built extension (python/CMakeLists.txt), so the
stubs always match the module: every function, class, method and property pybind11 exposes, with
the parameter and return types of its signature line and the first line of its docstring.

Usage: make_stubs.py EXTENSION_FILE OUTPUT.pyi
"""

import importlib.machinery
import importlib.util
import re
import sys


def load(path):
    loader = importlib.machinery.ExtensionFileLoader("_quadrix", path)
    spec = importlib.util.spec_from_file_location("_quadrix", path, loader=loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    return module


def python_type(text):
    """A pybind11 type name as a stub annotation."""
    text = text.strip()
    text = re.sub(r"numpy\.ndarray\[[^\]]*\]", "numpy.ndarray", text)
    text = re.sub(r"\b(?:quadrix\.)?_quadrix\.", "", text)
    text = re.sub(r"\bquadrix\.", "", text)
    text = re.sub(r"\b(?:object|handle)\b", "Any", text)
    return text


def split_parameters(text):
    """Splits a parameter list at top-level commas."""
    parts, depth, current = [], 0, ""
    for c in text:
        if c in "[(":
            depth += 1
        elif c in "])":
            depth -= 1
        if c == "," and depth == 0:
            parts.append(current)
            current = ""
        else:
            current += c
    if current.strip():
        parts.append(current)
    return [p.strip() for p in parts]


def parameter(text):
    if text in ("*", "/") or text.startswith("*"):
        return text
    name, _, rest = text.partition(":")
    annotation, has_default, default = rest.partition("=")
    annotation = python_type(annotation) if annotation.strip() else "Any"
    if not has_default:
        return "%s: %s" % (name.strip(), annotation)
    default = default.strip()
    if not re.fullmatch(r"None|True|False|-?[0-9.e+-]+|'[^']*'|\"[^\"]*\"", default):
        default = "..."
    return "%s: %s = %s" % (name.strip(), annotation, default)


SIGNATURE = re.compile(r"^(?:\d+\. )?(\w+)\((.*)\) -> (.+)$")
ANY_SIGNATURE = re.compile(r"^(?:\d+\. )?\w*\(.*\) -> .+$")


def signatures(doc, name):
    """The (parameters, return type) of every signature line of a pybind11 docstring."""
    found = []
    for line in (doc or "").splitlines():
        match = SIGNATURE.match(line.strip())
        if match and match.group(1) == name:
            found.append(([parameter(p) for p in split_parameters(match.group(2))], python_type(match.group(3))))
    return found


def summary(doc):
    """The first paragraph of prose of a docstring (after the signature lines), on one line."""
    words = []
    for line in (doc or "").splitlines():
        line = line.strip()
        if not line or ANY_SIGNATURE.match(line) or line == "Overloaded function.":
            if words:
                break
            continue
        words.append(line)
    return " ".join(words).replace('"""', "'").replace("\\", "\\\\")


def function_stub(name, doc, indent="", method=False):
    found = signatures(doc, name) or [(["self"] if method else ["*args: Any", "**kwargs: Any"], "Any")]
    lines = []
    for parameters, result in found:
        if method and parameters and parameters[0].startswith("self"):
            parameters[0] = "self"
        if len(found) > 1:
            lines.append(indent + "@overload")
        lines.append(indent + "def %s(%s) -> %s:" % (name, ", ".join(parameters), result))
        text = summary(doc)
        lines.append(indent + "    " + ('"""%s"""' % text if text else "..."))
    return lines


def class_stub(name, cls):
    lines = ["class %s:" % name]
    text = summary(cls.__doc__)
    if text:
        lines.append('    """%s"""' % text)
    for member_name, member in sorted(vars(cls).items()):
        if member_name.startswith("_") and member_name not in ("__init__", "__len__", "__repr__", "__iter__",
                                                               "__getitem__", "__array__"):
            continue
        if isinstance(member, property):
            doc = member.fget.__doc__ if member.fget else ""
            own = summary(member.__doc__)
            match = re.search(r"\) -> (.+)$", (doc or "").splitlines()[0]) if doc else None
            result = python_type(match.group(1)) if match else "Any"
            lines.append("    @property")
            lines.append("    def %s(self) -> %s:" % (member_name, result))
            text = own or summary(doc)
            lines.append("        " + ('"""%s"""' % text if text else "..."))
        elif callable(member):
            if member_name == "__init__" and not signatures(member.__doc__, "__init__"):
                continue  # no constructor exposed
            lines += function_stub(member_name, member.__doc__, "    ", method=True)
    return lines


def main():
    module = load(sys.argv[1])
    out = ['"""Type stubs of the quadrix module (generated from its pybind11 signatures by make_stubs.py)."""',
           "", "from typing import Any, Dict, List, Optional, Tuple, Union, overload", "", "import numpy", "",
           "__version__: str", ""]
    for name in sorted(dir(module)):
        if name.startswith("_"):
            continue
        value = getattr(module, name)
        if isinstance(value, type):
            out += class_stub(name, value) + [""]
        elif callable(value):
            out += function_stub(name, value.__doc__) + [""]
        else:
            out += ["%s: %s" % (name, type(value).__name__), ""]
    with open(sys.argv[2], "w") as stream:
        stream.write("\n".join(out))


if __name__ == "__main__":
    main()
