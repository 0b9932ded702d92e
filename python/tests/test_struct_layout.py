"""The ctypes structures of the package against the structs of ``include/bingham.h``, field by field.

The library reads and writes these structs through the pointers the package passes, so a field
missing, added, reordered or of another type there shifts every field after it: no error, only
wrong numbers. A size check (``ctypes.sizeof``) misses a reordering or a ``double`` turned into a
``size_t``. So every ``typedef struct name { ... } name;`` of the header is parsed (field names,
order, C types, fixed arrays, pointers, function pointers) and compared with the ``_fields_`` of
the package's ``ctypes.Structure`` that mirrors it ("names, order and types"); a header struct
without a mirror fails unless :data:`EXEMPT` says why, and a Structure of the package that
mirrors no header struct fails too. The header is found from this file (``../../include``): the
package is tested installed, not from the checkout.
"""

import ctypes
import importlib
import inspect
import os
import pkgutil
import re

import pytest

import bingham

HEADER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "include", "bingham.h")

#: header struct -> the package's Structure mirroring it ("module.Class").
MIRRORS = {
    "bingham_nonlinear_options": "bingham.filter._Options",
    "bingham_nonlinear_report": "bingham.filter._Report",
    "bingham_ahrs_params": "bingham.ahrs.AhrsParams",
    "bingham_ahrs_health_report": "bingham.ahrs.AhrsHealth",
}

#: header structs the package does not mirror, each with its reason.
EXEMPT = {}

#: C scalar types -> ctypes.
SCALARS = {
    "double": ctypes.c_double,
    "float": ctypes.c_float,
    "size_t": ctypes.c_size_t,
    "int": ctypes.c_int,
    "unsigned": ctypes.c_uint,
    "unsigned int": ctypes.c_uint,
    "long": ctypes.c_long,
    "unsigned long": ctypes.c_ulong,
    "char": ctypes.c_char,
    "bool": ctypes.c_bool,
    "int8_t": ctypes.c_int8,
    "uint8_t": ctypes.c_uint8,
    "int16_t": ctypes.c_int16,
    "uint16_t": ctypes.c_uint16,
    "int32_t": ctypes.c_int32,
    "uint32_t": ctypes.c_uint32,
    "int64_t": ctypes.c_int64,
    "uint64_t": ctypes.c_uint64,
}


def _strip_comments(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    return re.sub(r"//[^\n]*", " ", text)


def _split_top(text, sep):
    """``text`` split at ``sep`` outside parentheses."""
    parts, depth, cur = [], 0, ""
    for ch in text:
        depth += {"(": 1, ")": -1}.get(ch, 0)
        if ch == sep and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    parts.append(cur)
    return [p.strip() for p in parts if p.strip()]


class Header:
    """The structs, function pointer typedefs, enums and integer macros of a C header."""

    def __init__(self, text):
        code = _strip_comments(text)
        self.macros = {m: int(v) for m, v in re.findall(r"^\s*#define (\w+) (\d+)\s*$", code, re.M)}
        self.enums = set()
        for tag, name in re.findall(r"typedef enum\s*(\w*)\s*\{.*?\}\s*(\w+);", code, re.S):
            self.enums |= {tag, name} - {""}
        #: typedef name -> (return type, [parameter types]) of function pointer typedefs
        self.fn_types = {}
        for ret, name, params in re.findall(r"typedef ([\w\s\*]+?)\s*\(\*\s*(\w+)\)\s*\(([^;]*)\);", code):
            self.fn_types[name] = (ret.strip(), self._params(params))
        #: struct name -> [(field, C declaration)] in order
        self.structs = {}
        for tag, body, name in re.findall(r"typedef struct (\w+) \{(.*?)\} (\w+);", code, re.S):
            assert tag == name, f"typedef struct {tag} {{...}} {name}: tag and name differ"
            fields = []
            for decl in (d.strip() for d in body.split(";")):
                if decl:
                    fields.extend(self._declarators(decl))
            self.structs[name] = fields
        self.opaque = set(re.findall(r"typedef struct (\w+) \1;", code))

    def _params(self, params):
        """The types of a parameter list (``void`` is none)."""
        return [self._param_type(p) for p in _split_top(params, ",") if p != "void"]

    def _param_type(self, param):
        """The type of a function parameter (its name, if it has one, dropped)."""
        m = re.match(r"^(.*?[\s\*])(\w+)$", param.strip())
        type_words = set(SCALARS) | {"void", "signed", "short", "long"} | self.enums | set(self.fn_types)
        if m and m.group(2) not in type_words and m.group(1).strip() not in ("struct", "enum", "const"):
            return m.group(1).strip()
        return param.strip()

    def _declarators(self, decl):
        """``(name, ("var", base type, pointer depth, [array sizes]))`` or, for a function
        pointer, ``(name, ("fn", return type, [parameter types]))`` for each declarator of a field
        declaration."""
        fn = re.match(r"^([\w\s\*]+?)\s*\(\*\s*(\w+)\)\s*\((.*)\)$", decl, re.S)
        if fn:
            ret, name, params = fn.groups()
            return [(name, ("fn", ret.strip(), self._params(params)))]
        m = re.match(r"^((?:const\s+|struct\s+|enum\s+|unsigned\s+)*\w+)\s*(.*)$", decl, re.S)
        assert m, f"cannot read the field declaration {decl!r}"
        base, rest = m.group(1), m.group(2)
        out = []
        for d in _split_top(rest, ","):
            dm = re.match(r"^(\**)\s*(?:const\s+)?(\w+)((?:\s*\[\s*\w+\s*\])*)$", d)
            assert dm, f"cannot read the declarator {d!r} of {decl!r}"
            stars, name, dims = dm.groups()
            out.append((name, ("var", base, len(stars), re.findall(r"\[\s*(\w+)\s*\]", dims))))
        return out

    def dim(self, d):
        return int(d) if d.isdigit() else self.macros[d]

    def ctype(self, spec, mirrors):
        """The ctypes type of a field's C type; for pointers to structs, a set of acceptable ones."""
        if spec[0] == "fn":
            _, ret, params = spec
            return ("fn", self.scalar_or_pointer(ret, mirrors), [self.scalar_or_pointer(p, mirrors) for p in params])
        _, base, stars, dims = spec
        t = self.scalar_or_pointer(base + " " + "*" * stars, mirrors)
        for d in reversed(dims):
            t = ("array", t, self.dim(d))
        return t

    def scalar_or_pointer(self, ctext, mirrors):
        """A C type as text (``const double *``, ``struct bingham_filter *``) -> its ctypes type,
        or a tuple describing the acceptable ones."""
        text = re.sub(r"\bconst\b", " ", ctext)
        stars = text.count("*")
        base = " ".join(text.replace("*", " ").split())
        base = re.sub(r"^(struct|enum) ", "", base)
        if stars == 0:
            if base in self.enums:
                return ctypes.c_int
            if base in self.fn_types:
                ret, params = self.fn_types[base]
                args = [self.scalar_or_pointer(p, mirrors) for p in params]
                return ("fn", self.scalar_or_pointer(ret, mirrors), args)
            if base in SCALARS:
                return SCALARS[base]
            if base in mirrors:
                return ("struct", base)
            raise AssertionError(f"no ctypes equivalent known for the C type {ctext!r}")
        if stars == 1 and base == "void":
            return ctypes.c_void_p
        if stars == 1 and base == "char":
            return ("any", ctypes.c_char_p, ctypes.POINTER(ctypes.c_char))
        if stars == 1 and (base in self.opaque or base in self.structs):
            # a handle or a struct by pointer: void * or a pointer to its mirror
            return ("any", ctypes.c_void_p, ("pointer", ("struct", base)))
        inner = self.scalar_or_pointer(base + " " + "*" * (stars - 1), mirrors)
        if isinstance(inner, tuple):
            return ("pointer", inner)
        return ctypes.POINTER(inner)


def matches(want, got, classes):
    """Whether the ctypes type ``got`` is what ``want`` (from :meth:`Header.ctype`) describes;
    ``classes`` maps header struct names to the package's Structures."""
    if not isinstance(want, tuple):
        return got is want
    kind = want[0]
    if kind == "any":
        return any(matches(w, got, classes) for w in want[1:])
    if kind == "struct":
        return got is classes.get(want[1])
    if kind == "pointer":
        return isinstance(got, type) and issubclass(got, ctypes._Pointer) and matches(want[1], got._type_, classes)
    if kind == "array":
        return (
            isinstance(got, type)
            and issubclass(got, ctypes.Array)
            and got._length_ == want[2]
            and matches(want[1], got._type_, classes)
        )
    if kind == "fn":
        return (
            isinstance(got, type)
            and issubclass(got, ctypes._CFuncPtr)
            and matches(want[1], got._restype_, classes)
            and len(got._argtypes_) == len(want[2])
            and all(matches(w, g, classes) for w, g in zip(want[2], got._argtypes_))
        )
    raise AssertionError(f"unknown type description {want!r}")


def describe(t):
    if isinstance(t, tuple):
        return "(" + ", ".join(describe(x) for x in t) + ")"
    if isinstance(t, list):
        return "[" + ", ".join(describe(x) for x in t) + "]"
    return getattr(t, "__name__", repr(t))


def package_structures():
    """Every ctypes Structure / Union defined in a module of the package: {"module.Class": cls}."""
    found = {}
    modules = [bingham] + [importlib.import_module(f"bingham.{m.name}") for m in pkgutil.iter_modules(bingham.__path__)]
    for mod in modules:
        for name, obj in vars(mod).items():
            if (
                inspect.isclass(obj)
                and issubclass(obj, (ctypes.Structure, ctypes.Union))
                and obj.__module__ == mod.__name__
            ):
                found[f"{mod.__name__}.{name}"] = obj
    return found


@pytest.fixture(scope="module")
def header():
    with open(HEADER, encoding="utf-8") as f:
        return Header(f.read())


@pytest.fixture(scope="module")
def classes():
    found = package_structures()
    return {c_name: found[path] for c_name, path in MIRRORS.items() if path in found}


def test_the_header_parser_reads_what_it_must(header):
    # positive control on the real header: every struct definition read, and a few fields the
    # library has always had
    with open(HEADER, encoding="utf-8") as f:
        definitions = re.findall(r"^typedef struct \w+ \{$", f.read(), re.M)
    assert len(header.structs) == len(definitions) >= 4, (sorted(header.structs), definitions)
    assert {"bingham_ahrs_params", "bingham_ahrs_health_report", "bingham_nonlinear_options"} <= set(header.structs)
    assert header.structs["bingham_ahrs_params"][0] == ("sample_time", ("var", "double", 0, []))
    assert ("max_calls", ("var", "size_t", 0, [])) in header.structs["bingham_nonlinear_options"]
    assert header.ctype(("var", "int32_t", 0, []), MIRRORS) is ctypes.c_int32
    assert "bingham_filter" in header.opaque and "bingham_status" in header.enums
    assert set(header.fn_types) == {"bingham_transition_fn", "bingham_log_likelihood_fn"}
    # the forms the header does not use yet, on a made-up one
    h = Header(
        """
        #define N_AXES 3
        typedef enum color { RED = 0 } color;
        typedef struct handle handle;
        typedef int (*cb)(const double *x, void *user_data);
        typedef struct inner { double a; } inner;
        typedef struct outer {
            /* a comment; with a semicolon */
            double x[N_AXES], y;   // two declarators
            const double *p;
            uint32_t m[2][4];
            bool flag;
            color c;
            handle *h;
            inner in;
            const char *name;
            cb fn;
            int (*raw)(double, int *);
        } outer;
        """
    )
    fields = dict(h.structs["outer"])
    assert list(fields) == ["x", "y", "p", "m", "flag", "c", "h", "in", "name", "fn", "raw"]
    k = {"inner": type("Inner", (ctypes.Structure,), {"_fields_": [("a", ctypes.c_double)]})}
    mirrors = {"inner": "x.Inner"}
    t = {f: h.ctype(spec, mirrors) for f, spec in fields.items()}
    ok = {
        "x": ctypes.c_double * 3,
        "y": ctypes.c_double,
        "p": ctypes.POINTER(ctypes.c_double),
        "m": (ctypes.c_uint32 * 4) * 2,
        "flag": ctypes.c_bool,
        "c": ctypes.c_int,
        "h": ctypes.c_void_p,
        "in": k["inner"],
        "name": ctypes.c_char_p,
        "fn": ctypes.CFUNCTYPE(ctypes.c_int, ctypes.POINTER(ctypes.c_double), ctypes.c_void_p),
        "raw": ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_double, ctypes.POINTER(ctypes.c_int)),
    }
    for f, want in t.items():
        assert matches(want, ok[f], k), f
    # and mismatches are seen
    assert not matches(t["x"], ctypes.c_double * 4, k)
    assert not matches(t["m"], (ctypes.c_uint32 * 2) * 4, k)
    assert not matches(t["y"], ctypes.c_size_t, k)
    assert not matches(t["p"], ctypes.POINTER(ctypes.c_float), k)
    assert not matches(t["fn"], ctypes.CFUNCTYPE(ctypes.c_int, ctypes.c_void_p, ctypes.c_void_p), k)


def test_every_header_struct_has_a_mirror(header):
    for name, reason in EXEMPT.items():
        assert name in header.structs, f"{name} is exempted but the header defines no such struct"
        assert name not in MIRRORS, f"{name} is exempted but mirrored"
        assert len(reason.split()) >= 5, f"the exemption of {name} needs its reason"
    unmirrored = sorted(set(header.structs) - set(MIRRORS) - set(EXEMPT))
    assert not unmirrored, (
        f"include/bingham.h defines {unmirrored} without a ctypes Structure in the package: add one "
        "(and its entry in MIRRORS here), or exempt it in EXEMPT with the reason"
    )
    stale = sorted(set(MIRRORS) - set(header.structs))
    assert not stale, f"MIRRORS names {stale}, which include/bingham.h does not define"


def test_every_package_structure_mirrors_a_header_struct():
    found = package_structures()
    assert "bingham.ahrs.AhrsParams" in found, sorted(found)
    unknown = sorted(set(found) - set(MIRRORS.values()))
    assert not unknown, f"the package defines ctypes structures {unknown} that mirror no header struct in MIRRORS"
    missing = sorted(set(MIRRORS.values()) - set(found))
    assert not missing, f"MIRRORS names {missing}, which the package does not define"


@pytest.mark.parametrize("c_name", sorted(MIRRORS))
def test_fields_match_the_header(header, classes, c_name):
    cls = classes[c_name]
    want = header.structs[c_name]
    got = list(cls._fields_)
    assert not getattr(cls, "_pack_", 0), f"{cls.__name__} sets _pack_; the header's struct is not packed"
    assert [f[0] for f in got] == [f[0] for f in want], (
        f"{cls.__name__} has the fields {[f[0] for f in got]}, {c_name} in include/bingham.h "
        f"{[f[0] for f in want]} (names and order must agree)"
    )
    for (name, spec), (_, ctype, *bits) in zip(want, got):
        assert not bits, f"{cls.__name__}.{name} is a bit field"
        expected = header.ctype(spec, MIRRORS)
        assert matches(expected, ctype, classes), (
            f"{cls.__name__}.{name} is {describe(ctype)}, but {c_name}.{name} in include/bingham.h "
            f"is {spec} -> {describe(expected)}"
        )
