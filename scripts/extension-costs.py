#!/usr/bin/env python3
"""What a new variant of each extensible kind touches (docs/extending.md, "Extension costs").

Usage: scripts/extension-costs.py [--list [KIND] | --check | --techniques]

Reads every tracked `.rs` file (`git ls-files`), code only: the `tests/` crate, every
`tests/` folder, `#[cfg(test)]` items and the modules they declare (`mod tests;`) are left
out; fuzz targets, benches, examples and build scripts are in. For each kind it counts:

- variants: the enums a new one is added to;
- matches: `match` expressions whose arm patterns name every variant of one of the
  kind's enums with no catch-all arm (the compiler reports each);
- tables: array literals naming every variant or every variant's name (`ALL`, `NAMES`,
  `PASSES`), and matches whose arm values name every variant (the parser's name arms,
  the fuzz targets' generators): they compile unchanged;
- silent: sites deciding by two or more named variants, which compile unchanged:
  `matches!` or an `if let` / `let ... else` pattern over two or more, a `match` naming
  two or more (but not every) variant with a catch-all arm (`_ =>`, a binding,
  `Some(_)`);
- one-variant tests: `==` or `!=` against a variant, `matches!` or a `let` pattern of
  one, a `match` naming one variant with a catch-all: an identity test (is this the
  Shade pass) or a property in disguise (`primitive == Primitive::Skins` for "joins
  sample views"); only reading tells, so they are counted apart (`--list` prints them).

A variant is named as `Enum::Variant` (any path prefix) or `Self::Variant` inside an
`impl` of the enum. A site is counted once per kind even if it names several of the
kind's enums. With `--list`, every site is printed as `file:line category enum`; with
`--check`, the table is compared with the one in docs/extending.md (exit status 1 if they
differ).

With `--techniques`: the lists naming three or more bundled techniques (`techniques/`)
by hand, tests included.
"""

import re
import subprocess
import sys
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# kind -> [(enum name, the file declaring it)]
KINDS = {
    "pass kind": [
        ("PassKind", "compiler/src/front/ast.rs"),
        ("IrPassKind", "compiler/src/ir/passes.rs"),
        ("PassKind", "graph/src/schema.rs"),
    ],
    "draw": [("Draw", "graph/src/schema.rs")],
    "builtin function": [("Func", "compiler/src/builtins/functions.rs")],
    "builtin input": [("Input", "compiler/src/builtins/inputs.rs")],
    "light kind": [
        ("LightKind", "graph/src/lights.rs"),
        ("LightModel", "graph/src/lights.rs"),
        ("Light", "runtime/light/src/lib.rs"),
    ],
    "Geometry primitive": [("Primitive", "compiler/src/front/ast.rs")],
}

TOKEN = re.compile(
    r"""
    (?P<ws>\s+)
  | (?P<line>//[^\n]*)
  | (?P<block>/\*)
  | (?P<raw>b?r\#*")
  | (?P<str>b?"(?:\\.|[^"\\])*")
  | (?P<char>b?'(?:\\(?:x[0-9a-fA-F]{2}|u\{[0-9a-fA-F]+\}|.)|[^\\'])')
  | (?P<life>'[A-Za-z_][A-Za-z0-9_]*)
  | (?P<ident>r\#[A-Za-z_][A-Za-z0-9_]*|[A-Za-z_][A-Za-z0-9_]*)
  | (?P<num>[0-9][0-9A-Za-z_]*(?:\.[0-9][0-9A-Za-z_]*)?)
  | (?P<punct>::|=>|==|!=|->|\.\.=|\.\.\.|\.\.|&&|\|\||<=|>=|<<=|>>=|\+=|-=|\*=|/=|%=|\^=|&=|\|=|.)
    """,
    re.VERBOSE | re.DOTALL,
)


class Tok:
    __slots__ = ("kind", "text", "line")

    def __init__(self, kind, text, line):
        self.kind, self.text, self.line = kind, text, line

    def __repr__(self):
        return f"{self.text}@{self.line}"


def tokenize(src):
    toks, i, line = [], 0, 1
    while i < len(src):
        m = TOKEN.match(src, i)
        kind = m.lastgroup
        if kind == "block":
            depth, j = 1, i + 2
            while depth and j < len(src):
                if src.startswith("/*", j):
                    depth, j = depth + 1, j + 2
                elif src.startswith("*/", j):
                    depth, j = depth - 1, j + 2
                else:
                    j += 1
            end = j
        elif kind == "raw":
            hashes = m.group().count("#")
            close = '"' + "#" * hashes
            end = src.index(close, m.end()) + len(close)
        else:
            end = m.end()
        text = src[i:end]
        if kind not in ("ws", "line", "block"):
            toks.append(Tok("str" if kind == "raw" else kind, text, line))
        line += text.count("\n")
        i = end
    return toks


OPEN, CLOSE = {"(": ")", "[": "]", "{": "}"}, {")", "]", "}"}


def matching(toks, i):
    """Index of the bracket closing the one at `i`."""
    depth = 0
    for j in range(i, len(toks)):
        t = toks[j].text
        if toks[j].kind == "punct" and t in OPEN:
            depth += 1
        elif toks[j].kind == "punct" and t in CLOSE:
            depth -= 1
            if depth == 0:
                return j
    return len(toks) - 1


def strip_tests(toks):
    """The tokens minus `#[cfg(test)]` items."""
    out, i = [], 0
    while i < len(toks):
        if (
            toks[i].text == "#"
            and i + 1 < len(toks)
            and toks[i + 1].text == "["
            and [t.text for t in toks[i + 2 : i + 7]] == ["cfg", "(", "test", ")", "]"]
        ):
            j = i + 7
            while j < len(toks) and toks[j].text not in ("{", ";"):
                j += 1
            i = (matching(toks, j) if j < len(toks) and toks[j].text == "{" else j) + 1
            continue
        out.append(toks[i])
        i += 1
    return out


def test_modules(files):
    """Files that `#[cfg(test)] mod name;` declares."""
    out = set()
    for f in files:
        src = (ROOT / f).read_text()
        for m in re.finditer(r"#\[cfg\(test\)\]\s*(?:pub\s+)?mod\s+(\w+)\s*;", src):
            d = Path(f).parent
            if Path(f).name not in ("mod.rs", "lib.rs", "main.rs"):
                d = d / Path(f).stem
            for cand in (d / f"{m.group(1)}.rs", d / m.group(1) / "mod.rs"):
                out.add(str(cand))
    return out


def code_files():
    files = subprocess.run(
        ["git", "ls-files", "*.rs"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    files = [f for f in files if not f.startswith("tests/") and "/tests/" not in f]
    skip = test_modules(files)
    return [f for f in files if f not in skip]


def enum_variants(toks, name):
    for i, t in enumerate(toks):
        if t.text == "enum" and i + 1 < len(toks) and toks[i + 1].text == name:
            j = i + 2
            while toks[j].text != "{":
                j += 1
            end, variants, k = matching(toks, j), [], j + 1
            while k < end:
                if toks[k].text == "#":  # an attribute
                    k = matching(toks, k + 1) + 1
                    continue
                variants.append(toks[k].text)
                k += 1
                while k < end and toks[k].text != ",":
                    k = matching(toks, k) + 1 if toks[k].text in OPEN else k + 1
                k += 1
            return variants
    raise SystemExit(f"enum {name} not found")


def impl_regions(toks):
    """(start, end, type name) of every `impl ... { }` block."""
    out = []
    for i, t in enumerate(toks):
        if t.kind != "ident" or t.text != "impl":
            continue
        j = i + 1
        while j < len(toks) and toks[j].text not in ("{", ";", "where"):
            j = matching_angle(toks, j) + 1 if toks[j].text == "<" else j + 1
        head = [x.text for x in toks[i + 1 : j]]
        if head and head[0] == "<":  # impl<T>
            head = head[matching_angle(toks, i + 1) - i :]
        if "for" in head:
            head = head[head.index("for") + 1 :]
        if "<" in head:
            head = head[: head.index("<")]
        while j < len(toks) and toks[j].text != "{":
            j += 1
        if head and j < len(toks):
            out.append((j, matching(toks, j), head[-1]))
    return out


def matching_angle(toks, i):
    """Index of the `>` closing the `<` at `i` (`->` and `=>` are tokens of their own)."""
    depth = 0
    for j in range(i, len(toks)):
        depth += toks[j].text == "<"
        depth -= toks[j].text == ">"
        if depth == 0:
            return j
    return len(toks) - 1


class FileScan:
    """The variant names at each token of one file: index -> (enum key, variant)."""

    def __init__(self, path, toks, enums):
        self.path, self.toks, self.named = path, toks, {}
        graph_pass_kind = path.startswith(("graph/", "runtime/", "lab/")) or bool(
            re.search(r"use sshc_graph::[^;]*\bPassKind\b", (ROOT / path).read_text())
        )
        impls = impl_regions(toks)
        for i in range(len(toks) - 2):
            a, sep, v = toks[i], toks[i + 1], toks[i + 2]
            if sep.text != "::" or a.kind != "ident" or v.kind != "ident":
                continue
            if i + 3 < len(toks) and toks[i + 3].text == "::":
                continue  # `Enum::Variant::...` is not a variant
            name = a.text
            if name == "Self":
                inside = [n for (s, e, n) in impls if s < i < e]
                if not inside:
                    continue
                name = inside[-1]
            for key, (ename, efile, variants) in enums.items():
                if ename != name or v.text not in variants:
                    continue
                if ename == "PassKind":
                    prefix = toks[i - 2].text if i >= 2 and toks[i - 1].text == "::" else None
                    schema = prefix in ("graph", "sshc_graph") or (prefix is None and graph_pass_kind)
                    if a.text == "Self":
                        schema = efile == path if efile.startswith("graph/") else path.startswith("graph/")
                    if schema != efile.startswith("graph/"):
                        continue
                self.named[i + 2] = (key, v.text)

    def names(self, lo, hi):
        """(enum key, variant) named in tokens lo..hi."""
        return [self.named[k] for k in range(lo, hi) if k in self.named]


def split_arms(toks, lo, hi):
    """The arms of a match block (tokens lo+1..hi-1): [(pattern range, value range)]."""
    arms, i = [], lo + 1
    while i < hi:
        p0 = i
        while i < hi and toks[i].text != "=>":
            i = matching(toks, i) + 1 if toks[i].text in OPEN else i + 1
        p1, i = i, i + 1
        v0, block_like = i, toks[i].text in ("{", "if", "match", "loop", "unsafe", "while", "for", "async")
        while i < hi:
            t = toks[i].text
            if t == ",":
                break
            if t in OPEN:
                i = matching(toks, i) + 1
                if t == "{" and block_like and i < hi and toks[i].text not in ("else", ".", "?", "as"):
                    break
                continue
            i += 1
        arms.append(((p0, p1), (v0, i)))
        if i < hi and toks[i].text == ",":
            i += 1
    return arms


def catch_all(toks, lo, hi, scan, enum_keys):
    """Whether a pattern matches what it names no variant of: `_`, a binding, `Some(_)`."""
    if any(k in enum_keys for k, _ in scan.names(lo, hi)):
        return False
    texts = [t.text for t in toks[lo:hi]]
    if "if" in texts:
        texts = texts[: texts.index("if")]
    if len(texts) == 1 and (texts[0] == "_" or (toks[lo].kind == "ident" and texts[0][0].islower())):
        return True
    return "_" in texts or ".." in texts


def scan_file(path, toks, enums, kinds_of):
    """Sites in one file: [(line, kind, category, enum)]."""
    scan = FileScan(path, toks, enums)
    sites = []

    def add(line, per_kind):
        # per_kind: kind -> (category, enum); one site per kind
        for kind, (cat, ename) in per_kind.items():
            sites.append((line, kind, cat, ename))

    def variants_by_enum(names):
        out = defaultdict(set)
        for key, v in names:
            out[key].add(v)
        return out

    RANK = {"match": 0, "table": 1, "silent": 2, "one-variant": 3}

    def best(per_kind, kind, cat, ename):
        if kind not in per_kind or RANK[cat] < RANK[per_kind[kind][0]]:
            per_kind[kind] = (cat, ename)

    # every match block, to leave nested matches out of an outer match's arm values
    blocks = []
    for i, t in enumerate(toks):
        if t.kind == "ident" and t.text == "match" and (i == 0 or toks[i - 1].text not in (".", "::")):
            j = i + 1
            while j < len(toks) and toks[j].text != "{":
                j = matching(toks, j) + 1 if toks[j].text in ("(", "[") else j + 1
            if j < len(toks):
                blocks.append((j, matching(toks, j)))

    arrays = [(i, matching(toks, i)) for i, t in enumerate(toks) if t.text == "[" and t.kind == "punct"]

    def nested(k, lo, hi):
        """Whether token k lies in a match or an array literal inside lo..hi."""
        return any(lo < a and b < hi and a < k < b for a, b in blocks + arrays)

    for i, t in enumerate(toks):
        # declarations
        if t.text == "enum" and i + 1 < len(toks):
            for key, (ename, efile, _) in enums.items():
                if efile == path and toks[i + 1].text == ename:
                    sites.append((t.line, kinds_of[key], "variant", ename))
        # match expressions
        if t.kind == "ident" and t.text == "match" and (i == 0 or toks[i - 1].text not in (".", "::")):
            j = i + 1
            while j < len(toks) and toks[j].text != "{":
                j = matching(toks, j) + 1 if toks[j].text in ("(", "[") else j + 1
            if j >= len(toks):
                continue
            end = matching(toks, j)
            arms = split_arms(toks, j, end)
            per_kind = {}
            for key, (ename, _, variants) in enums.items():
                kind = kinds_of[key]
                pat = variants_by_enum(n for a in arms for n in scan.names(*a[0]))[key]
                # an arm's value, less the matches nested in it (sites of their own)
                val = variants_by_enum(
                    scan.named[k] for a in arms for k in range(*a[1]) if k in scan.named and not nested(k, j, end)
                )[key]
                wild = any(catch_all(toks, *a[0], scan, {key}) for a in arms)
                if pat == set(variants) and not wild:
                    best(per_kind, kind, "match", ename)
                elif len(pat) >= 2:
                    best(per_kind, kind, "silent", ename)
                elif len(pat) == 1 and wild:
                    best(per_kind, kind, "one-variant", ename)
                elif not pat and val == set(variants):
                    best(per_kind, kind, "table", ename)
            add(t.line, per_kind)
        # matches!(expr, pattern)
        if t.text == "matches" and i + 2 < len(toks) and toks[i + 1].text == "!" and toks[i + 2].text in OPEN:
            end, k = matching(toks, i + 2), i + 3
            while k < end and toks[k].text != ",":
                k = matching(toks, k) + 1 if toks[k].text in OPEN else k + 1
            per_kind = {}
            for key, vs in variants_by_enum(scan.names(k, end)).items():
                best(per_kind, kinds_of[key], "silent" if len(vs) >= 2 else "one-variant", enums[key][0])
            add(t.line, per_kind)
        # `if let`, `while let`, `let ... else`: the pattern up to its `=`
        if t.kind == "ident" and t.text == "let":
            k = i + 1
            while k < len(toks) and toks[k].text not in ("=", ";"):
                k = matching(toks, k) + 1 if toks[k].text in OPEN else k + 1
            per_kind = {}
            for key, vs in variants_by_enum(scan.names(i + 1, k)).items():
                best(per_kind, kinds_of[key], "silent" if len(vs) >= 2 else "one-variant", enums[key][0])
            add(t.line, per_kind)
        # ==, !=
        if t.text in ("==", "!=") and t.kind == "punct":
            per_kind = {}
            # the variant ends the left operand or is the path starting the right one
            k = i + 1
            while k < len(toks) and toks[k].text == "&":
                k += 1
            while k + 2 < len(toks) and toks[k].kind == "ident" and toks[k + 1].text == "::":
                k += 2
            for k in (i - 1, k):
                if k in scan.named:
                    key, _ = scan.named[k]
                    best(per_kind, kinds_of[key], "one-variant", enums[key][0])
            add(t.line, per_kind)
        # array literals: their own elements (depth one) naming variants
        if t.text == "[" and t.kind == "punct":
            end, direct, depth = matching(toks, i), defaultdict(set), 0
            for k in range(i + 1, end):
                x = toks[k].text
                if x in OPEN:
                    depth += 1
                elif x in CLOSE:
                    depth -= 1
                elif depth == 0 and k in scan.named and toks[k - 2].text in ("Self", scan.named[k][0][0]):
                    m = k - 2
                    while toks[m - 1].text == "::":  # a path prefix
                        m -= 2
                    if toks[m - 1].text in ("[", ",", "&"):
                        direct[scan.named[k][0]].add(scan.named[k][1])
            per_kind = {}
            strings = [x for x in toks[i + 1 : end] if x.text != ","]
            if strings and all(x.kind == "str" for x in strings):
                # a table of the variants' names (`PASSES`, `Primitive::NAMES`)
                for key, (ename, _, variants) in enums.items():
                    if sorted(x.text.strip('"') for x in strings) == sorted(variants):
                        best(per_kind, kinds_of[key], "table", ename)
            for key, vs in direct.items():
                if vs == set(enums[key][2]):
                    best(per_kind, kinds_of[key], "table", enums[key][0])
            add(t.line, per_kind)
    return sites


def technique_lists():
    """Lists naming three or more bundled techniques by hand, tests included: array
    literals and matches (the innermost holding three names), as (file, line, names)."""
    names = {p.stem for p in (ROOT / "techniques").glob("*.ron")}

    def technique(tok):
        if tok.kind != "str":
            return None
        t = tok.text.strip('"').removeprefix("techniques/").removesuffix(".ron")
        return t if t in names else None

    files = subprocess.run(
        ["git", "ls-files", "*.rs"], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.split()
    out = []
    for f in files:
        toks = tokenize((ROOT / f).read_text())
        spans = []
        for i, t in enumerate(toks):
            if t.text == "[" and t.kind == "punct":
                spans.append((i, matching(toks, i)))
            elif t.kind == "ident" and t.text == "match" and (i == 0 or toks[i - 1].text != "."):
                j = i + 1
                while j < len(toks) and toks[j].text != "{":
                    j = matching(toks, j) + 1 if toks[j].text in ("(", "[") else j + 1
                if j < len(toks):
                    spans.append((j, matching(toks, j)))
        found = [(a, b, {technique(toks[k]) for k in range(a, b)} - {None}) for a, b in spans]
        found = [(a, b, n) for a, b, n in found if len(n) >= 3]
        for a, b, n in found:
            if not any(a < c and d < b for c, d, _ in found):
                out.append((f, toks[a].line, sorted(n)))
    return out


def main():
    args = sys.argv[1:]
    if "--techniques" in args:
        lists = technique_lists()
        for f, line, n in lists:
            print(f"{f}:{line} {len(n)}: {' '.join(n)}")
        print(f"{len(lists)} lists in {len({f for f, _, _ in lists})} files")
        return
    listing = "--list" in args
    only = " ".join(a for a in args if a not in ("--list", "--check")) or None
    files = code_files()
    tokens = {f: strip_tests(tokenize((ROOT / f).read_text())) for f in files}
    enums, kinds_of = {}, {}
    for kind, decls in KINDS.items():
        for ename, efile in decls:
            key = (ename, efile)
            enums[key] = (ename, efile, enum_variants(tokens[efile], ename))
            kinds_of[key] = kind
    sites = []
    for f in files:
        for line, kind, cat, ename in scan_file(f, tokens[f], enums, kinds_of):
            sites.append((kind, f, line, cat, ename))
    if listing:
        for kind, f, line, cat, ename in sorted(sites):
            if only is None or kind == only:
                print(f"{kind}: {f}:{line} {cat} {ename}")
        return
    rows = [
        "| a new ... | places | variants | matches | tables | silent | files | one-variant tests (files) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for kind in KINDS:
        mine = [s for s in sites if s[0] == kind]
        count = lambda c: sum(1 for s in mine if s[3] == c)
        places = [s for s in mine if s[3] != "one-variant"]
        ones = [s for s in mine if s[3] == "one-variant"]
        rows.append(
            f"| {kind} | {len(places)} | {count('variant')} | {count('match')} | {count('table')} | "
            f"{count('silent')} | {len({s[1] for s in places})} | {len(ones)} ({len({s[1] for s in ones})}) |"
        )
    if "--check" in args:
        doc = (ROOT / "docs" / "extending.md").read_text()
        if "\n".join(rows) not in doc:
            print("docs/extending.md's table differs from the code's counts:", *rows, sep="\n")
            sys.exit(1)
        print("docs/extending.md's table agrees with the code")
        return
    print("\n".join(rows))


if __name__ == "__main__":
    main()
