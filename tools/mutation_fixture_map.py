# Appended by tools/mutation.py to the conftest.py of a layer's copy of the tests (never loaded in
# the repository's own test runs).
#
# mutmut maps each mutated function to the tests that called it while its stats run was going:
# a function called by a module- or session-scoped fixture is mapped only to the first test that
# set the fixture up, so its mutants are checked against that one test while every later test
# reading the fixture's result could catch them.  These hooks record the functions each module-,
# class-, package- or session-scoped fixture called while it was set up, and, when the stats run
# ends, map them to every test that uses that fixture (the same fixture at the same place: one
# module's module fixture is not another module's).  Only the calls made by the fixture's own
# set-up count: a session fixture every test reaches (pytest's tmp_path_factory) does not drag the
# functions of other fixtures along.
import os as _mutation_os

import pytest as _mutation_pytest

_MUTATION_FIXTURE_CALLS: dict[tuple[str, ...], set[str]] = {}


def _mutation_stats_run() -> bool:
    return _mutation_os.environ.get("MUTANT_UNDER_TEST") == "stats"


def _mutation_nodeid(item) -> str:  # type: ignore[no-untyped-def]
    return item.nodeid.removeprefix("mutants/")


def _mutation_where(scope: str, path) -> str:  # type: ignore[no-untyped-def]
    """Where one instance of a fixture of ``scope`` lives, from a path in it (a test's or the node's)."""
    if scope == "session":
        return ""
    if scope == "package":
        return str(path if path.is_dir() else path.parent)
    return str(path)  # module and class fixtures: one instance per test file (a class's is finer)


@_mutation_pytest.hookimpl(hookwrapper=True)
def pytest_fixture_setup(fixturedef, request):  # type: ignore[no-untyped-def]
    scope = str(fixturedef.scope)
    if not _mutation_stats_run() or scope == "function":
        yield
        return
    from mutmut.state import state

    before = set(state()._stats)
    yield
    called = set(state()._stats) - before
    if called:
        node_path = getattr(request.node, "path", None)
        key = (fixturedef.argname, fixturedef.baseid, scope, _mutation_where(scope, node_path))
        _MUTATION_FIXTURE_CALLS.setdefault(key, set()).update(called)


def _mutation_shared_fixtures(item) -> list[tuple[str, ...]]:  # type: ignore[no-untyped-def]
    info = getattr(item, "_fixtureinfo", None)
    keys = []
    for name, defs in info.name2fixturedefs.items() if info is not None else ():
        scope = str(getattr(defs[-1], "scope", "function"))
        if scope != "function":
            keys.append((name, defs[-1].baseid, scope, _mutation_where(scope, item.path)))
    return keys


def pytest_sessionfinish(session):  # type: ignore[no-untyped-def]
    if not _mutation_stats_run():
        return
    from mutmut.state import state

    table = state().tests_by_mangled_function_name
    for item in getattr(session, "items", []):
        for key in _mutation_shared_fixtures(item):
            for function in _MUTATION_FIXTURE_CALLS.get(key, ()):
                table[function].add(_mutation_nodeid(item))
