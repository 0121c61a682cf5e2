"""Prove the small-int bound: load a firmware module with every arithmetic result checked.

`load(name)` compiles firmware/<name>.py again with each BinOp, UnaryOp and AugAssign result
wrapped in a check that raises `SmallIntOverflow` when an int reaches 2**30 in magnitude (the
small-int limit of MicroPython on ESP32/RP2040). Hypothesis then drives the instrumented
functions over the whole input space: if no example raises, no intermediate left the range.
`stats.max_abs` keeps the largest magnitude seen, so tests can also report the headroom.
"""
import ast
import importlib
import os
import types

LIMIT = 1 << 30


class SmallIntOverflow(AssertionError):
    pass


class Stats:
    def __init__(self):
        self.max_abs = 0
        self.where = None


def _make_check(stats, limit, filename):
    def _chk(v, line):
        if type(v) is int:
            a = -v if v < 0 else v
            if a > stats.max_abs:
                stats.max_abs = a
                stats.where = line
            if a >= limit:
                raise SmallIntOverflow("%s:%d: intermediate %d leaves the small-int range"
                                       % (filename, line, v))
        return v
    return _chk


class _Wrap(ast.NodeTransformer):
    def _wrap(self, node):
        return ast.copy_location(ast.Call(
            func=ast.Name(id="_chk__", ctx=ast.Load()),
            args=[node, ast.Constant(value=node.lineno)], keywords=[]), node)

    def visit_BinOp(self, node):
        self.generic_visit(node)
        return self._wrap(node)

    def visit_UnaryOp(self, node):
        self.generic_visit(node)
        if isinstance(node.op, ast.Not):
            return node
        return self._wrap(node)

    def visit_AugAssign(self, node):
        # x op= y  ->  x op= y ; _chk__(x)   (the target re-read after the update)
        self.generic_visit(node)
        load = ast.parse(ast.unparse(node.target), mode="eval").body
        check = ast.Expr(value=self._wrap(ast.copy_location(load, node)))
        ast.fix_missing_locations(check)
        return [node, ast.copy_location(check, node)]


def load(name, limit=LIMIT):
    """Return (module, stats) for firmware.<name>, instrumented."""
    mod = importlib.import_module("firmware." + name)
    path = mod.__file__
    src = open(path).read()
    tree = _Wrap().visit(ast.parse(src, path))
    ast.fix_missing_locations(tree)
    stats = Stats()
    new = types.ModuleType("firmware." + name + "__checked")
    new.__file__ = path
    new.__dict__["_chk__"] = _make_check(stats, limit, os.path.basename(path))
    exec(compile(tree, path, "exec"), new.__dict__)
    return new, stats
