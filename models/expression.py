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
from typing import Callable

import casadi as ca

from models.errors import MechanismError

FUNCTIONS: dict[str, Callable] = {
    "sin": ca.sin, "cos": ca.cos, "tan": ca.tan,
    "asin": ca.asin, "acos": ca.acos, "atan": ca.atan, "atan2": ca.atan2,
    "sinh": ca.sinh, "cosh": ca.cosh, "tanh": ca.tanh,
    "exp": ca.exp, "log": ca.log, "sqrt": ca.sqrt, "abs": ca.fabs,
}
ARITY = {name: (2 if name == "atan2" else 1) for name in FUNCTIONS}
CONSTANTS = {"pi": math.pi, "e": math.e}
_OPERATORS = {ast.Add: lambda a, b: a + b, ast.Sub: lambda a, b: a - b, ast.Mult: lambda a, b: a * b,
              ast.Div: lambda a, b: a / b, ast.Pow: lambda a, b: a**b}
MAX_LENGTH = 2000


def compile_expression(text: str, pointer: str, variable: str = "u",
                       names: tuple[str, ...] = ()) -> Callable[..., ca.SX]:
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
        _check(tree.body, pointer, allowed)
    except RecursionError:
        raise MechanismError(pointer, "expression nested too deeply") from None
    return lambda u, env=None: _build(tree.body, {**(env or {}), variable: u})


def _not_allowed(pointer: str, what: str, names: set[str]) -> MechanismError:
    functions = ", ".join(sorted(FUNCTIONS))
    variables = ", ".join(sorted(names))
    return MechanismError(pointer, f"unsafe or unsupported expression: {what} is not allowed "
                                   f"(use numbers, {variables}, pi, e, + - * / ** and the functions {functions})")


def _check(node: ast.AST, pointer: str, names: set[str]) -> None:
    if isinstance(node, ast.Constant):
        if isinstance(node.value, bool) or not isinstance(node.value, (int, float)):
            raise _not_allowed(pointer, f"the constant {node.value!r}", names)
    elif isinstance(node, ast.Name):
        if node.id not in names and node.id not in CONSTANTS:
            raise _not_allowed(pointer, f"the name '{node.id}'", names)
    elif isinstance(node, ast.BinOp):
        if type(node.op) not in _OPERATORS:
            raise _not_allowed(pointer, f"the operator {type(node.op).__name__}", names)
        _check(node.left, pointer, names)
        _check(node.right, pointer, names)
    elif isinstance(node, ast.UnaryOp):
        if not isinstance(node.op, (ast.USub, ast.UAdd)):
            raise _not_allowed(pointer, f"the operator {type(node.op).__name__}", names)
        _check(node.operand, pointer, names)
    elif isinstance(node, ast.Call):
        name = node.func.id if isinstance(node.func, ast.Name) else None
        if name not in FUNCTIONS:
            label = f"a call of '{name}'" if name else "a call of a computed function"
            raise _not_allowed(pointer, label, names)
        if node.keywords or len(node.args) != ARITY[name]:
            raise MechanismError(pointer, f"{name}() takes {ARITY[name]} positional argument(s)")
        for arg in node.args:
            _check(arg, pointer, names)
    else:
        raise _not_allowed(pointer, f"a {type(node).__name__} expression", names)


def _build(node: ast.AST, env: dict):
    if isinstance(node, ast.Constant):
        return float(node.value)
    if isinstance(node, ast.Name):
        return env[node.id] if node.id in env else CONSTANTS[node.id]
    if isinstance(node, ast.BinOp):
        return _OPERATORS[type(node.op)](_build(node.left, env), _build(node.right, env))
    if isinstance(node, ast.UnaryOp):
        value = _build(node.operand, env)
        return -value if isinstance(node.op, ast.USub) else value
    args = [_build(a, env) for a in node.args]  # a checked Call
    return FUNCTIONS[node.func.id](*args)
