"""Safe math expressions in one variable (u, or another name), compiled into CasADi, never
evaluated by Python.

The text is parsed by Python's own parser (`ast`, mode "eval"), then walked with a whitelist:
numbers, the variable, named parameters the caller declares, the constants pi and e,
+ - * / ** and unary minus, and a fixed set of functions. Anything else (attributes, subscripts, names, keywords, comparisons, lambdas,
strings, calls of other functions such as __import__) is rejected with a message naming it.
"""

from __future__ import annotations

import ast
import math
from collections.abc import Callable

import casadi as ca

from flexmech.models.documents.fields import MAX_EXPRESSION_CHARS
from flexmech.models.errors import MechanismError

FUNCTIONS: dict[str, Callable] = {
    "sin": ca.sin,
    "cos": ca.cos,
    "tan": ca.tan,
    "asin": ca.asin,
    "acos": ca.acos,
    "atan": ca.atan,
    "atan2": ca.atan2,
    "sinh": ca.sinh,
    "cosh": ca.cosh,
    "tanh": ca.tanh,
    "exp": ca.exp,
    "log": ca.log,
    "sqrt": ca.sqrt,
    "abs": ca.fabs,
}
ARITY = {name: (2 if name == "atan2" else 1) for name in FUNCTIONS}
CONSTANTS = {"pi": math.pi, "e": math.e}
_OPERATORS = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
    ast.Pow: lambda a, b: a**b,
}
MAX_LENGTH = MAX_EXPRESSION_CHARS  # a document's expression fields are bounded by it too
MAX_DEPTH = 50  # nesting of operations and calls; Python's own recursion would overflow far later


def compile_expression(
    text: str, pointer: str, variable: str = "u", names: tuple[str, ...] = ()
) -> Callable[..., ca.SX]:
    """Check `text` now and return a builder: given the variable's SX (and a dict of the
    named parameters' SX, when `names` are declared), the expression's SX.

    Raises MechanismError(pointer, ...) for text that does not parse or is not allowed.
    """
    if not isinstance(text, str) or not text.strip():
        raise MechanismError(pointer, f"expected a non-empty expression in {variable}")
    if len(text) > MAX_LENGTH:
        raise MechanismError(pointer, f"expression longer than {MAX_LENGTH} characters")
    try:
        tree = ast.parse(text.strip(), mode="eval")
    except RecursionError:
        raise MechanismError(pointer, "expression nested too deeply") from None
    except SyntaxError as exc:
        column = f" at column {exc.offset}" if exc.offset else ""
        raise MechanismError(pointer, f"cannot parse expression {text!r}: {exc.msg}{column}") from None
    allowed = {variable, *names}
    try:
        depth = _check(tree.body, pointer, allowed)
    except RecursionError:
        raise MechanismError(pointer, "expression nested too deeply") from None
    if depth > MAX_DEPTH:
        raise MechanismError(pointer, f"expression nested too deeply (more than {MAX_DEPTH} levels)")
    return lambda u, env=None: _build(tree.body, {**(env or {}), variable: u})


def _not_allowed(pointer: str, what: str, names: set[str]) -> MechanismError:
    functions = ", ".join(sorted(FUNCTIONS))
    variables = ", ".join(sorted(names))
    return MechanismError(
        pointer,
        f"unsafe or unsupported expression: {what} is not allowed "
        f"(use numbers, {variables}, pi, e, + - * / ** and the functions {functions})",
    )


def _check(node: ast.AST, pointer: str, names: set[str]) -> int:
    """Raise for anything not allowed; return the nesting depth."""
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise _not_allowed(pointer, f"the constant {node.value!r}", names)
        return 1
    if isinstance(node, ast.Name):
        if node.id not in names and node.id not in CONSTANTS:
            raise _not_allowed(pointer, f"the name '{node.id}'", names)
        return 1
    if isinstance(node, ast.BinOp):
        if type(node.op) not in _OPERATORS:
            raise _not_allowed(pointer, f"the operator {type(node.op).__name__}", names)
        return 1 + max(_check(node.left, pointer, names), _check(node.right, pointer, names))
    if isinstance(node, ast.UnaryOp):
        if not isinstance(node.op, (ast.USub, ast.UAdd)):
            raise _not_allowed(pointer, f"the operator {type(node.op).__name__}", names)
        return 1 + _check(node.operand, pointer, names)
    if isinstance(node, ast.Call):
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in FUNCTIONS:
            label = f"a call of '{name}'" if name else "a call of a computed function"
            raise _not_allowed(pointer, label, names)
        if node.keywords or len(node.args) != ARITY[name]:
            raise MechanismError(pointer, f"{name}() takes {ARITY[name]} positional argument(s)")
        return 1 + max(_check(arg, pointer, names) for arg in node.args)
    kind = type(node).__name__
    raise _not_allowed(pointer, f"{'an' if kind[0] in 'AEIOU' else 'a'} {kind} expression", names)


def _build(node: ast.AST, env: dict):
    if isinstance(node, ast.Constant):
        # A CasADi number, not a Python float: 1/0 or 9**9**9 is then inf (and (-1)**0.5 nan),
        # never an exception or a complex number; finite_on() reports it with its field.
        return ca.DM(float(node.value)) if abs(node.value) < 1e308 else ca.DM(float("inf"))
    if isinstance(node, ast.Name):
        return env[node.id] if node.id in env else ca.DM(CONSTANTS[node.id])
    if isinstance(node, ast.BinOp):
        return _OPERATORS[type(node.op)](_build(node.left, env), _build(node.right, env))
    if isinstance(node, ast.UnaryOp):
        value = _build(node.operand, env)
        return -value if isinstance(node.op, ast.USub) else value
    args = [_build(a, env) for a in node.args]  # a checked Call
    return FUNCTIONS[node.func.id](*args)


def finite_on(
    build, pointer: str, at: tuple[float, ...], what: str = "u", env: dict | None = None, positive: bool = False
) -> None:
    """Evaluate a compiled expression at the values `at` of its variable (named numbers from
    env): MechanismError(pointer) where it is not a finite number (or not positive)."""
    for value in at:
        try:
            result = float(ca.DM(build(ca.DM(value), env)))
        except (RuntimeError, TypeError, ValueError, OverflowError):
            result = float("nan")
        if not math.isfinite(result):
            raise MechanismError(
                pointer,
                f"the expression is not a finite number at {what} = {value:g} "
                "(a division by zero, an overflow, or a root or logarithm of a negative number)",
            )
        if positive and result <= 0:
            raise MechanismError(pointer, f"the expression must be positive, and is {result:g} at {what} = {value:g}")
