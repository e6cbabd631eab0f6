"""Settings of the whole suite."""
import os

# The suite's two workers compile the same kernels and wait on each other's compile lock; the
# line that says such a wait (transient.jit) would land on a stderr that tests hold to one line
# 'error: ...' or to nothing. tests/test_jit.py sets it back to test that line.
os.environ.setdefault("TRANSIENT_LOCK_NOTICE_S", "inf")
# the suite's setups are not this machine's record of its setups (transient.setuptimes)
os.environ.setdefault("TRANSIENT_SETUP_LOG", "off")

# Each of the suite's workers takes its share of the cores for OpenMP, MKL and OpenBLAS, set
# before any of them loads: with each worker's runtimes on every core, the workers' threads
# outnumber the cores and wait on one another. A count the user set is kept. The tests of
# several threads (marked every_core) run in a process of their own that has every core
# (tests/test_blas.py), rather than pass here on one thread without testing what they say.
_workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))
if _workers > 1 and "TRANSIENT_THREADS_SHARE" not in os.environ:
    _share = str(max(1, len(os.sched_getaffinity(0)) // _workers))
    _set = [n for n in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")
            if n not in os.environ]
    os.environ.update({n: _share for n in _set}, TRANSIENT_THREADS_SHARE=" ".join(_set))

# the suite runs as the command line does, with the settings that speed it up (an import
# alone makes none: tests/test_configure.py)
import transient  # noqa: E402

transient.configure()


# the instances of parametrized tests over about a second whose other instances are quick;
# whole tests that slow are marked where they are defined (`pytest -m "not slow"`)
SLOW_INSTANCES = {
    "test_bar_on_a_rigid_wall[implicit]", "test_bar_on_a_rigid_wall[implicit-lumped-superlu]",
    "test_bar_on_a_rigid_wall[implicit-reduced]", "test_outputs_stored_are_those_asked_for[True]",
    "test_kernel_equals_its_twin[newmark_full-friction]",
    "test_kernel_equals_its_twin[newmark_reduced-friction]",
    "test_kernel_equals_its_twin[exponential_implicit-friction]",
    "test_energy_balance_holds_with_every_scheme_and_converges_at_second_order"
    "[False-implicit-None]",
    "test_the_contact_and_the_factorization_read_only_what_their_keys_hold[case1-more1]",
    "test_exact_tie_is_the_constrained_problem[rule0]",
    "test_exact_tie_is_the_constrained_problem[rule2]",
    "test_reduced_model_agrees_with_the_full_one_without_contact[explicit]",
    "test_reduced_model_agrees_with_the_full_one_without_contact[exponential]",
    "test_a_mirrored_outboard_pad_has_the_modes_of_one_built_in_place[tet10 gmsh]",
    "test_plot_cea_draws_the_diagram_the_unstable_shapes_and_the_mu_map[basis1]"}


def pytest_collection_modifyitems(items):
    """Mark SLOW_INSTANCES slow; a name there whose test is collected but not that instance
    (a renamed parameter) stops the run, rather than going back to the quick subset."""
    import pytest
    names = {item.name for item in items}
    functions = {item.originalname for item in items if hasattr(item, "originalname")}
    stale = sorted(n for n in SLOW_INSTANCES if n not in names and n.split("[")[0] in functions)
    if stale:
        raise pytest.UsageError(f"tests/conftest.py SLOW_INSTANCES: no such instance {stale}")
    shared = os.environ.get("TRANSIENT_THREADS_SHARE", "").split()
    for item in items:
        if item.name in SLOW_INSTANCES:
            item.add_marker(pytest.mark.slow)
        if shared and item.get_closest_marker("every_core"):
            item.add_marker(pytest.mark.skip(
                reason=f"{' '.join(shared)} at this worker's share: run by "
                       "tests/test_blas.py::test_every_core_tests_in_a_process_of_their_own"))
