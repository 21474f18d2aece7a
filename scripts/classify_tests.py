#!/usr/bin/env python3
"""Classify every test of the workspace as independent / self-consistency /
behaviour (issue 24's audit), and flag assertions that may pass when their
quantity doubles or vanishes.

Usage: scripts/classify_tests.py [--list] [--weak]

Tests: Rust `#[test]` functions (proptest's included) in model-core, analysis,
host-cli, python and tests/ (the firmware's own crate is left out), and the
pytest `test_*` functions in python/tests.

Classification (by the text of the test's body and doc comment, first rule
that applies; a reading aid, not a proof — see the counts' caveat in the
audit note):

* independent: the expected value comes from a computation that shares no
  code with the code under test: the brute force over springs
  (`springs::`, `brute`), the fixed-step scheme against the exact solvers
  (`fixed(`, `fixed_bounded`, `run_dimensionless`, `fixed_step`), closed
  forms written in the test (`closed form`, `asin(`, `acos(`, `PI`, `tgamma`,
  hand-computed frames `by hand`, `hand-built`), exhaustive proofs,
  Richardson/self-convergence of a reference, a known value quoted from the
  paper or a datasheet (`paper`, `RM0090`);
* self-consistency: numbers compared with numbers of the same code (other
  tolerance, mirrored drive, f32 vs f64, other units, tighter run,
  `agrees`, `symmetry`, `invariance`), recognised by a numeric comparison
  (`abs() <=`, `< tol`, `assert_eq!` on floats, `pytest.approx`,
  `isclose`) without an independent marker;
* behaviour: everything else: refusals and their messages, exit codes,
  files, JSON keys, protocol round trips, flags, threads, panics.

Before the body is read, the test's name decides two cases: a wiring or
dispatch check, or one front end against another (`wiring`, `dispatch`,
`is_the_`, `uses_the`, `matches_cli`, `matches_model_core`) is
self-consistency, and a name about refusals, messages, flags, outputs and
files (`refus`, `bad_input`, `message`, `json`, `csv`, `plot`, `exit`, …)
is behaviour.

`--weak` lists one-sided or sign-only numeric assertions (`> 0.0`,
`< 1.0`, `!= 0`, `is_finite()` alone) for a reader to check whether they
would pass if the quantity doubled or vanished.
"""

import os
import re
import sys
from collections import Counter, defaultdict

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
RUST_DIRS = ["model-core", "analysis", "host-cli", "python/src", "tests"]
PY_DIRS = ["python/tests"]

INDEPENDENT = re.compile(
    r"springs::|brute|fixed\(|fixed_bounded|fixed_warm|run_dimensionless|fixed_step::|"
    r"closed[- ]form|\basin\(|\bacos\(|tgamma|by hand|hand-built|built by hand|hand-computed|"
    r"exhaustive|Richardson|self-convergence|extrapolat|paper'?s? (value|eq|table)|RM0090|"
    r"normal_brute_force|integration_tests::fixed|quadrature written|layer-cake|"
    r"transfer function|Runge|RK4|first order|order of|regression's|"
    r"independent",
    re.I,
)
SELF = re.compile(
    r"abs\(\)\s*<=?|<=?\s*tol|\.abs\(\) <|assert_eq!\([^;]*\b(mu|value|m\d|r\d)\b|"
    r"pytest\.approx|isclose|allclose|agrees|symmetr|invarian|f32.*f64|tighter|"
    r"\bgap\b|within",
    re.I,
)
WEAK = re.compile(
    r"assert!\([^;]*?(>\s*0(\.0)?\b|<\s*1(\.0)?\s*[,)]|!=\s*0(\.0)?\b|is_finite\(\)\s*[,)])"
    r"|assert [^\n]*(> 0\b|> 0\.0\b|< 1\.0?\b)"
)


def rust_tests(path):
    text = open(path, encoding="utf-8").read()
    out = []
    for m in re.finditer(r"#\[test\]", text):
        fn = re.compile(r"\bfn\s+(\w+)").search(text, m.end())
        if not fn:
            continue
        # Doc comment / attributes above the #[test].
        head_start = text.rfind("\n\n", 0, m.start())
        head = text[head_start + 1 if head_start >= 0 else 0 : m.start()]
        brace = text.find("{", fn.end())
        depth, i = 0, brace
        while i < len(text):
            c = text[i]
            if c == "{":
                depth += 1
            elif c == "}":
                depth -= 1
                if depth == 0:
                    break
            i += 1
        body = text[brace : i + 1]
        line = text.count("\n", 0, fn.start()) + 1
        out.append((fn.group(1), line, head, body))
    return out


def py_tests(path):
    lines = open(path, encoding="utf-8").read().split("\n")
    out = []
    for i, l in enumerate(lines):
        m = re.match(r"(\s*)def (test_\w+)", l)
        if not m:
            continue
        ind = len(m.group(1))
        j = i + 1
        while j < len(lines) and (not lines[j].strip() or len(lines[j]) - len(lines[j].lstrip()) > ind):
            j += 1
        out.append((m.group(2), i + 1, "", "\n".join(lines[i:j])))
    return out


BEHAVIOUR_NAME = re.compile(
    r"refus|bad_input|bad_inputs|reject|errors_name|_errors$|message|names_the_flag|help|keys|"
    r"json|csv|png|svg|plot|aligned|roundtrip|round_trip|timeout|times_out|exit|overwrite|"
    r"threads|panic|progress|flag|writes|output|usage|^every_|silent|busy",
    re.I,
)
WIRING_NAME = re.compile(
    r"wiring|dispatch|is_the_|uses_the|matches_cli|matches_the_cli|matches_model_core|"
    r"_cli$|against_the_cli|as_the_cli",
    re.I,
)


def classify(name, head, body):
    text = head + "\n" + body
    if WIRING_NAME.search(name):
        return "self-consistency"
    if BEHAVIOUR_NAME.search(name):
        return "behaviour"
    if INDEPENDENT.search(text):
        return "independent"
    if SELF.search(body):
        return "self-consistency"
    return "behaviour"


def files():
    for d in RUST_DIRS:
        for dp, dn, fn in os.walk(os.path.join(ROOT, d)):
            dn[:] = [x for x in dn if x not in ("target", ".venv", "node_modules")]
            for f in fn:
                if f.endswith(".rs"):
                    yield os.path.join(dp, f), rust_tests
    for d in PY_DIRS:
        for dp, _, fn in os.walk(os.path.join(ROOT, d)):
            for f in fn:
                if f.startswith("test_") and f.endswith(".py"):
                    yield os.path.join(dp, f), py_tests


def main():
    show_list = "--list" in sys.argv
    show_weak = "--weak" in sys.argv
    total = Counter()
    per_crate = defaultdict(Counter)
    rows = []
    weak = []
    for path, reader in sorted(files()):
        rel = os.path.relpath(path, ROOT)
        crate = rel.split("/")[0] if not rel.startswith("python/tests") else "python/tests"
        for name, line, head, body in reader(path):
            kind = classify(name, head, body)
            total[kind] += 1
            per_crate[crate][kind] += 1
            rows.append((rel, line, name, kind))
            for m in WEAK.finditer(body):
                ln = line + body.count("\n", 0, m.start())
                weak.append((rel, ln, name, m.group(0).strip()[:90]))
    kinds = ["independent", "self-consistency", "behaviour"]
    print(f"{'crate':<14}" + "".join(f"{k:>18}" for k in kinds) + f"{'total':>8}")
    for crate in sorted(per_crate):
        c = per_crate[crate]
        print(f"{crate:<14}" + "".join(f"{c[k]:>18}" for k in kinds) + f"{sum(c.values()):>8}")
    print(f"{'all':<14}" + "".join(f"{total[k]:>18}" for k in kinds) + f"{sum(total.values()):>8}")
    if show_list:
        for r in rows:
            print(f"{r[3]:<17} {r[0]}:{r[1]} {r[2]}")
    if show_weak:
        print(f"\n{len(weak)} one-sided or sign-only assertions to read:")
        for w in weak:
            print(f"{w[0]}:{w[1]} {w[2]}: {w[3]}")


if __name__ == "__main__":
    main()
