"""One vector pass instead of a loop: CasADi's C code of `fn.map(lanes)`, rewritten so that
every instruction of fn's straight-line SX code works on all lanes at once.

CasADi generates an SX Function as straight-line C, one statement per operation on
scalar locals (`a0012=(a0007*a0011);`), and its map as a loop calling that code once
per column. walker3d's dynamics Hessian element is ~194 000 such statements; node after
node they take ~85 us per node (2-core AMD EPYC, -O1). Here the locals become GCC vectors
of `lanes` doubles (`__attribute__((vector_size))`), the loads gather the lanes' inputs
and the stores scatter them, comparisons and selections become masks, and functions (of
the C library, or CasADi's helpers such as casadi_sign) are called lane by lane. Each lane
performs exactly the scalar code's operations in the same order (IEEE arithmetic, no
contraction into fused multiply-adds: compile with -ffp-contract=off), so the results are
bit for bit those of the loop. With AVX2, four nodes a pass, ~30 us per node (2026-11-23).

The kernel ends with `vzeroupper` when built for AVX: GCC did not clear the upper halves
of the registers at its return, and the SSE code that runs next (CasADi's virtual
machine, MUMPS) then ran ~60 % slower (walker2d's constraint evaluations inside IPOPT: 15
-> 25 ms a solve).

`vectorize_map` raises `Unsupported` for a statement it does not know; the caller then
compiles CasADi's loop as it is.
"""

from __future__ import annotations

import re

LANES = 4  # nodes per vector pass: one AVX2 register of doubles

# comparisons and logic: (a op b) -> 1.0 or 0.0, as the scalar code stores them
LOGIC = {"<=": "v_le", ">=": "v_ge", "==": "v_eq", "!=": "v_ne", "<": "v_lt", ">": "v_gt",
         "&&": "v_and", "||": "v_or"}

_VAR = r"a\d+"
_NUM = r"-?(?:\d+\.?\d*|\.\d+)(?:e[-+]?\d+)?"
_CONSTANT = rf"(?:{_NUM}|-?casadi_inf|casadi_nan)"
_OPERAND = rf"(?:{_VAR}|{_NUM})"
_SIGNATURE = (r"const casadi_real\*\* arg, casadi_real\*\* res, casadi_int\* iw, "
              r"casadi_real\* w, int mem\)")


class Unsupported(ValueError):
    """The code has a statement (or a layout) this rewriter does not know."""


def vectorize_map(code: str, lanes: int = LANES) -> str:
    """The C code of a CasADi map over `lanes` columns (`CodeGenerator` output of
    `fn.map(lanes)` for an SX fn) with the same functions and API, computing all columns
    in one pass of vector operations. Raises Unsupported."""
    loop = re.search(rf"static int (casadi_f\d+)\({_SIGNATURE} \{{\n  casadi_int i;\n.*?\n"
                     r"  return 0;\n\}", code, re.S)
    if loop is None or f"for (i=0; i<{lanes}; ++i) {{" not in loop[0]:
        raise Unsupported(f"no map over {lanes} columns in the code")
    called = re.findall(r"if \((casadi_f\d+)\(arg1, res1, iw, w, 0\)\) return 1;", loop[0])
    if len(called) != 1:
        raise Unsupported("the map does not call exactly one function")
    kernel = called[0]
    strides = {kind: {int(i): int(s) for i, s in re.findall(
        rf"if \({kind}1\[(\d+)\]\) {kind}1\[\1\]\+=(\d+);", loop[0])} for kind in ("arg", "res")}
    body = re.search(rf"static int {kernel}\({_SIGNATURE} \{{\n(.*?)\n  return 0;\n\}}",
                     code, re.S)
    if body is None:
        raise Unsupported(f"{kernel} is not straight-line code")
    statements = [_vector_statement(line, strides) for line in body[1].split("\n")]
    new_kernel = (f"static int {kernel}(const casadi_real** arg, casadi_real** res, "
                  f"casadi_int* iw, casadi_real* w, int mem) {{\n" + "\n".join(statements)
                  + "\n#ifdef __AVX__\n  __builtin_ia32_vzeroupper();\n#endif\n  return 0;\n}")
    new_loop = loop[0].split("{", 1)[0] + f"{{\n  return {kernel}(arg, res, iw, w, mem);\n}}"
    return code.replace(body[0], _prelude(lanes) + new_kernel).replace(loop[0], new_loop)


def _vector_statement(line: str, strides: dict) -> str:
    s = line.strip()
    if s.startswith("casadi_real "):  # the declarations of the locals
        return "  vreal " + s[len("casadi_real "):]
    m = re.fullmatch(rf"({_VAR})=arg\[(\d+)\]\? arg\[\2\]\[(\d+)\] : 0;", s)
    if m:
        return f"  {m[1]}=v_load(arg[{m[2]}], {m[3]}, {_stride(strides['arg'], m[2])});"
    m = re.fullmatch(rf"if \(res\[(\d+)\]!=0\) res\[\1\]\[(\d+)\]=({_OPERAND});", s)
    if m:
        return (f"  v_store(res[{m[1]}], {m[2]}, {_stride(strides['res'], m[1])}, "
                f"{_vector(m[3])});")
    m = re.fullmatch(rf"({_VAR})=(.+);", s)
    if m is None:
        raise Unsupported(f"statement {s!r}")
    target, rhs = m[1], m[2]
    for pattern, vector in _RULES:
        m = re.fullmatch(pattern, rhs)
        if m:
            return f"  {target}={vector(m)};"
    raise Unsupported(f"statement {s!r}")


# The right-hand sides of the kernel's assignments, as vector expressions
_RULES = [
    (_CONSTANT, lambda m: f"v_all({m[0]})"),
    # arithmetic: GCC applies scalar constants to every lane
    (rf"\((?:-{_VAR}|{_OPERAND}[-+*/]{_OPERAND})\)", lambda m: m[0]),
    *((rf"\(({_OPERAND}){re.escape(op)}({_OPERAND})\)",
       lambda m, name=name: f"{name}({_vector(m[1])},{_vector(m[2])})")
      for op, name in LOGIC.items()),
    (rf"\(!({_VAR})\)", lambda m: f"v_not({m[1]})"),
    (rf"\(({_VAR})\?({_OPERAND}):({_OPERAND})\)",
     lambda m: f"v_select({m[1]},{_vector(m[2])},{_vector(m[3])})"),
    (rf"casadi_sq\(({_VAR})\)", lambda m: f"({m[1]}*{m[1]})"),
    (rf"(\w+)\(({_VAR})\)", lambda m: f"v_call1({m[1]},{m[2]})"),
    (rf"(\w+)\(({_VAR}),({_VAR})\)", lambda m: f"v_call2({m[1]},{m[2]},{m[3]})"),
]


def _stride(table: dict, index: str) -> int:
    if int(index) not in table:
        raise Unsupported(f"no stride for argument {index}")
    return table[int(index)]


def _vector(operand: str) -> str:
    return operand if re.fullmatch(_VAR, operand) else f"v_all({operand})"


def _prelude(lanes: int) -> str:
    def each(expr: str) -> str:
        return "{" + ", ".join(expr.format(b=b) for b in range(lanes)) + "}"

    loop = f"int b; for (b = 0; b < {lanes}; ++b)"
    lines = [
        "#include <math.h>",
        f"typedef double vreal __attribute__((vector_size({8 * lanes})));",
        f"typedef long long vmask __attribute__((vector_size({8 * lanes})));",
        f"#define v_all(c) ((vreal){each('(c)')})",
        # a mask (-1 where true) as the scalar code's 1.0 / 0.0
        "static inline vreal v_truth(vmask m) { return (vreal)(m & (vmask)v_all(1.0)); }",
        "static inline vreal v_not(vreal a) { return v_truth(a == v_all(0.0)); }",
        "static inline vreal v_select(vreal c, vreal x, vreal y) {"
        " vmask m = (c != v_all(0.0)); return (vreal)((m & (vmask)x) | (~m & (vmask)y)); }",
        "static inline vreal v_load(const casadi_real* p, casadi_int k, casadi_int s) {"
        f" if (!p) return v_all(0.0); return (vreal){each('p[k + {b} * s]')}; }}",
        "static inline void v_store(casadi_real* p, casadi_int k, casadi_int s, vreal v) {"
        f" if (!p) return; {{ {loop} p[k + b * s] = v[b]; }} }}",
        # a scalar function of one or two arguments, lane by lane (GCC statement expressions)
        f"#define v_call1(f, x) ({{ vreal r_; int b_; for (b_ = 0; b_ < {lanes}; ++b_)"
        " r_[b_] = f((x)[b_]); r_; })",
        f"#define v_call2(f, x, y) ({{ vreal r_; int b_; for (b_ = 0; b_ < {lanes}; ++b_)"
        " r_[b_] = f((x)[b_], (y)[b_]); r_; })",
    ]
    for op, name in LOGIC.items():
        if op in ("&&", "||"):
            c_op = "&" if op == "&&" else "|"
            lines.append(f"static inline vreal {name}(vreal a, vreal b) {{ return v_truth("
                         f"(a != v_all(0.0)) {c_op} (b != v_all(0.0))); }}")
        else:
            lines.append(f"static inline vreal {name}(vreal a, vreal b) {{ return v_truth(a {op} b); }}")
    return "\n".join(lines) + "\n"
