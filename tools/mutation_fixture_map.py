# Appended by tools/mutation.py to the conftest.py of a layer's copy of the tests (never loaded in
# the repository's own test runs).
#
# mutmut maps each mutated function to the tests that called it while its stats run was going:
# a function called by a module- or session-scoped fixture is mapped only to the first test that
# set the fixture up, so its mutants are checked against that one test while every later test
# reading the fixture's result could catch them.  These hooks record, for each test, the functions
# called before its body ran (its fixtures' set-up) and, when the stats run ends, map those
# functions to every test that shares one of the test's module-, class-, package- or
# session-scoped fixtures.
import os as _mutation_os

import pytest as _mutation_pytest

_MUTATION_SETUP_CALLS: dict[str, set[str]] = {}


def _mutation_stats_run() -> bool:
    return _mutation_os.environ.get("MUTANT_UNDER_TEST") == "stats"


def _mutation_nodeid(item) -> str:  # type: ignore[no-untyped-def]
    return item.nodeid.removeprefix("mutants/")


@_mutation_pytest.hookimpl(tryfirst=True)
def pytest_runtest_call(item):  # type: ignore[no-untyped-def]
    if _mutation_stats_run():
        from mutmut.state import state

        _MUTATION_SETUP_CALLS[_mutation_nodeid(item)] = set(state()._stats)


def _mutation_shared_fixtures(item) -> list[tuple[str, ...]]:  # type: ignore[no-untyped-def]
    info = getattr(item, "_fixtureinfo", None)
    keys = []
    for name, defs in info.name2fixturedefs.items() if info is not None else ():
        scope = str(getattr(defs[-1], "scope", "function"))
        if scope == "function":
            continue
        where = {"session": "", "package": str(item.path.parent)}.get(scope, str(item.path))
        keys.append((name, defs[-1].baseid, scope, where))
    return keys


def pytest_sessionfinish(session):  # type: ignore[no-untyped-def]
    if not _mutation_stats_run():
        return
    from mutmut.state import state

    sharing: dict[tuple[str, ...], set[str]] = {}
    keys_of: dict[str, list[tuple[str, ...]]] = {}
    for item in getattr(session, "items", []):
        keys = _mutation_shared_fixtures(item)
        keys_of[_mutation_nodeid(item)] = keys
        for key in keys:
            sharing.setdefault(key, set()).add(_mutation_nodeid(item))
    table = state().tests_by_mangled_function_name
    for nodeid, functions in _MUTATION_SETUP_CALLS.items():
        group: set[str] = set()
        for key in keys_of.get(nodeid, ()):
            group |= sharing[key]
        if group:
            for function in functions:
                table[function] |= group
