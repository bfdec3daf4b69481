import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))  # tests/naive.py

from nbst.problem import problem_from_dict  # noqa: E402


def make_problem(starts, radii=10.0, *, box=(800.0, 800.0), t_final=5.0, R=75.0, masses=None, cueable=None,
                 targets=None, name="test"):
    """A Problem from plain lists (targets default to the starts)."""
    n = len(starts)
    radii = np.broadcast_to(np.asarray(radii, float), (n,))
    disks = []
    for i in range(n):
        d = {"start": list(map(float, starts[i])),
             "target": list(map(float, (targets[i] if targets is not None else starts[i]))),
             "radius": float(radii[i])}
        if masses is not None:
            d["mass"] = float(masses[i])
        if cueable is not None:
            d["cueable"] = bool(cueable[i])
        disks.append(d)
    return problem_from_dict({"name": name, "box": list(box), "t_final": t_final, "target_radius": R,
                              "disks": disks})


@pytest.fixture
def mk():
    return make_problem


# --------------------------------------------------------------------------- compiled kernels, slow tests


# --------------------------------------------------------------------------- the two tiers
#
# The README's test command runs the fast tier on every core: ``pytest -n auto -m "not slow"``;
# CI (.ci/run) runs it, then the slow tier (``-m slow``), so CI still runs everything.
#
# The rule: a test that takes more than FAST_TEST_S seconds (warm numba cache, one core) belongs
# to the slow tier. Mark it ``@pytest.mark.slow`` where it is written (a new test), or list its node
# id below. A fast-tier test that runs past the budget is named at the end of the run.

#: Seconds a fast-tier test may take (warm caches) before the run's summary asks to mark it slow.
FAST_TEST_S = 3.0

#: The slow tier, by node id (a parametrized test is listed per case, or by its base id for all
#: of them): tests of seconds each (pytest --durations=0, 2 shared cores, warm numba cache, issues
#: 24 and 35), and end-to-end runs that a faster test of the same thing already covers in the fast tier.
SLOW = frozenset({
    "tests/test_signals.py::test_render_leaves_the_previous_video_and_no_partial_file",
    "tests/test_signals.py::test_solve_writes_the_best_so_far_whatever_the_signals",
    "tests/test_signals.py::test_experiment_keeps_only_whole_run_files",
    "tests/test_signals.py::test_solve_islands_die_with_their_parent_on_sigkill",
    "tests/test_signals.py::test_validate_writes_no_partial_report",
    "tests/test_signals.py::test_interrupt_once_raises_once_then_lets_the_cleanup_finish",
    "tests/test_search.py::test_where_the_crossing_bound_stops_the_event_cap_still_holds",
    "tests/test_baselines.py::test_meta_and_history",
    "tests/test_experiments.py::test_dask_cluster_equals_local",
    "tests/test_hardening_inputs.py::test_a_huge_file_of_any_shape_is_refused_fast_and_small",
    "tests/test_render_cli.py::test_figure_legends_sit_outside_the_box",
    "tests/test_hardening_inputs.py::test_report_html_escapes_the_name",
    "tests/test_hardening_inputs.py::test_validate_json_outputs_are_strict",
    "tests/test_models.py::test_report_legends_never_cover_data",
    "tests/test_aim.py::test_bank_shot_lands_exactly_when_the_path_is_clear",
    "tests/test_render_cli.py::test_3d_view_writes_a_still_and_a_short_video",
    "tests/test_aim.py::test_bank_shot_lands_exactly_when_the_path_is_clear[0-0]",
    "tests/test_aim.py::test_generate_cli",
    "tests/test_baselines.py::test_budget_is_exact[cma]",
    "tests/test_bowling.py::test_cli_atlas_writes_shots_and_resumes",
    "tests/test_bowling.py::test_cli_not_found_writes_the_nearest_and_exits_1",
    "tests/test_bowling.py::test_doc_replay_lines_give_the_shots_pins_without_nbst",
    "tests/test_bowling.py::test_interrupt_keeps_the_best_so_far",
    "tests/test_bowling.py::test_render_draws_the_ball_where_the_replay_has_it",
    "tests/test_bowling.py::test_rollouts_are_bit_identical_to_a_fresh_plain_replay",
    "tests/test_bowling.py::test_solve_finds_a_strike_within_a_small_budget",
    "tests/test_bowling.py::test_solve_is_reproducible_for_any_jobs",
    "tests/test_bowling_atlas.py::test_atlas_on_a_dask_cluster_writes_the_same_shots_as_one_thread",
    "tests/test_bowling_atlas.py::test_classes_cover_every_subset_and_single_pins",
    "tests/test_bowling_atlas.py::test_emitter_run_is_reproducible_for_any_jobs",
    "tests/test_bowling_hardening.py::test_atlas_from_the_shipped_atlas_unpacks_it",
    "tests/test_cli.py::test_bad_input_exits_2_one_line_no_traceback",
    "tests/test_cli.py::test_bad_solution_file_exit_2",
    "tests/test_cli.py::test_checkout_shim_runs",
    "tests/test_docs.py::test_every_command_in_the_doc_runs[README.md]",
    "tests/test_docs.py::test_every_command_in_the_doc_runs[bowling.md]",
    "tests/test_docs.py::test_every_command_in_the_doc_runs[experiments.md]",
    "tests/test_docs.py::test_every_command_in_the_doc_runs[install.md]",
    "tests/test_docs.py::test_every_command_in_the_doc_runs[mujoco.md]",
    "tests/test_docs.py::test_every_command_in_the_doc_runs[render.md]",
    "tests/test_docs.py::test_every_command_in_the_doc_runs[results/disks.md]",
    "tests/test_experiments.py::test_cli_ablation_outputs",
    "tests/test_experiments.py::test_cli_curves_outputs",
    "tests/test_experiments.py::test_process_pool_equals_in_process",
    "tests/test_hardening_inputs.py::test_inside_the_domain_loads_and_simulates_inside_the_box",
    "tests/test_hardening_outputs.py::test_experiment_workers_die_with_their_parent[15]",
    "tests/test_hardening_outputs.py::test_experiment_workers_die_with_their_parent[9]",
    "tests/test_hardening_outputs.py::test_render_sigterm_removes_its_partial_video",
    "tests/test_islands.py::test_islands_on_a_dask_cluster_give_the_local_solution",
    "tests/test_islands.py::test_one_job_is_the_plain_search",
    "tests/test_logs.py::test_a_second_warm_up_says_nothing",
    "tests/test_logs.py::test_solve_into_a_log_has_no_carriage_returns",
    "tests/test_models.py::test_report_legends_never_cover_data[overlay_figure]",
    "tests/test_models.py::test_report_page_reads_well",
    "tests/test_models_validate.py::test_cli_mjcf_and_validate_report",
    "tests/test_packaging.py::test_pip_install_into_a_fresh_venv[pip-install-e]",
    "tests/test_packaging.py::test_pip_install_into_a_fresh_venv[pip-install]",
    "tests/test_packaging.py::test_wheel_holds_only_nbst",
    "tests/test_planner.py::test_every_simulation_is_a_trial_counted_at_the_simulator",
    "tests/test_robust.py::test_reproducible_from_the_seed",
    "tests/test_search.py::test_a_legal_problem_never_yields_a_refused_solution[A]",
    "tests/test_search.py::test_a_legal_problem_never_yields_a_refused_solution[nbst]",
    "tests/test_search.py::test_ctrl_c_writes_the_best_so_far",
    "tests/test_search.py::test_variants_behave",
    "tests/test_sensitivity.py::test_transition_from_an_intermediate_time_is_the_jacobian_of_the_rest",
    "tests/test_setup.py::test_is_cold_sees_numba_disk_cache",
    "tests/test_sim.py::test_agrees_with_brute_force_integrator",
    "tests/test_stepping.py::test_cli_aligned_convergence_report",
    "tests/test_stepping.py::test_newton_cradle_passes_the_impulse_along",
    "tests/test_stepping.py::test_simultaneous_three_disk_contact_follows_the_exact_order",
    # issue 35: measured in the fast tier at 5-70 s each (2 cores, load 7), most of them bowling runs
    "tests/test_docs.py::test_every_command_in_the_doc_runs",
    "tests/test_robust.py::test_more_robust_than_the_plain_best",
    "tests/test_robust.py::test_robust_eval_is_the_worst_cost_and_the_and_over_the_shifted_runs",
    "tests/test_many.py::test_progress_reports_the_best_motion_and_how_near_the_stop_is",
    "tests/test_many.py::test_nbst_solve_on_a_many_disk_file",
    "tests/test_bowling_frame.py::test_bowl_spares_is_reproducible_from_its_seed_and_refuses_bad_input_in_one_line",
    "tests/test_bowling_frame.py::test_a_noisy_estimate_is_reproducible_from_its_seed_on_any_number_of_processes",
    "tests/test_bowling_foul_atlas.py::test_grow_is_reproducible_from_the_seed_on_one_and_two_processes",
    "tests/test_bowling_foul_atlas.py::test_noisy_throws_harvest_new_subsets_with_themselves_as_elites",
    "tests/test_bowling_foul_atlas.py::test_the_probability_counts_exactly_the_subset",
    "tests/test_bowling_foul_atlas.py::test_cli_solve_from_the_foul_line_answers_from_the_atlas_with_a_probability",
    "tests/test_bowling_foul_atlas.py::test_the_mirror_step_throws_the_other_hand_once_per_unmirrored_subset",
    "tests/test_bowling_foul_atlas.py::test_seek_grows_the_archive_with_what_its_children_knock_down",
    "tests/test_bowling_robust.py::test_maximise_is_reproducible_from_its_seed_on_1_and_2_processes",
    "tests/test_bowling_robust.py::test_maximise_with_want_climbs_towards_an_exact_outcome_and_keeps_it_on_the_ladder",
    "tests/test_render_bowling_lane.py::test_cli_writes_a_still_and_an_mp4_with_the_expected_frames",
    "tests/test_render_bowling_lane.py::test_the_recording_is_the_frame_run_frame_runs",
    "tests/test_render_bowling_lane.py::test_cli_replay_films_a_throw_file_and_refuses_a_shot_file_in_one_line",
    "tests/test_bowling_hardening.py::test_solve_leave_answers_from_the_shipped_atlas",
    "tests/test_bowling_contacts.py::test_ball_pin_and_pin_pin_are_varied_apart",
    "tests/test_baselines.py::test_improves_on_a_trivial_problem",
    "tests/test_render.py::test_figures_of_many_disks_leave_the_numbers_out_and_say_so",
    "tests/test_render_cli.py::test_a_thousand_disk_problem_renders_to_mp4_and_png",
})

#: Test files that time a command (signals sent after a delay, Ctrl-C during a run): their tests
#: run after ``compiled_kernels``, so a cold numba cache (~50 s on 2 cores) never lands inside one.
TIMED_FILES = frozenset({"tests/test_search.py", "tests/test_hardening_outputs.py", "tests/test_cli.py"})


@pytest.fixture(scope="session")
def compiled_kernels():
    """Compile every numba kernel of the main job once per session (or load it from numba's
    on-disk cache: ~1-3 s warm), before the first test that times something."""
    from nbst.warmup import warm_all

    return warm_all()


@pytest.fixture(autouse=True)
def _kernels_before_timed_tests(request):
    if request.node.nodeid.split("::")[0] in TIMED_FILES:
        request.getfixturevalue("compiled_kernels")


def pytest_collection_modifyitems(config, items):
    """Mark the tests of SLOW (node ids, parametrized ones by their base id) ``slow``, so that
    ``pytest -m "not slow"`` is the fast tier; a plain ``pytest`` runs everything."""
    for item in items:
        if item.nodeid in SLOW or item.nodeid.split("[")[0] in SLOW:
            item.add_marker(pytest.mark.slow)
    items.sort(key=lambda it: -LONGEST.get(it.nodeid, 0.0))  # stable: the rest keep their order


#: The slow tier's longest tests (seconds, ``pytest -m slow --durations``, 2 cores, 2026-12-06, 22:35 UTC):
#: they are handed out first, so that the last minutes of ``-n auto`` are not one long test on
#: one core while the other idles (longest first; the order of the rest is pytest's).
LONGEST = {
    "tests/test_crash_run.py::test_the_benchmarks_planted_scripts_ask_two_contacts_and_their_hidden_intents_meet_them": 121,
    "tests/test_docs.py::test_every_command_in_the_doc_runs[bowling.md]": 96,
    "tests/test_docs.py::test_every_command_in_the_doc_runs[README.md]": 90,
    "tests/test_docs.py::test_every_command_in_the_doc_runs[render.md]": 86,
    "tests/test_crash_run.py::test_a_planted_script_with_min_p_has_a_hidden_answer_its_noisy_drivers_meet_that_often": 66,
    "tests/test_crash_reconstruct.py::test_a_noise_free_planted_head_on_has_intervals_that_hold_the_truth_and_conserve_momentum": 41,
    "tests/test_setup.py::test_the_groups_compile_no_kernel_in_common": 38,
    "tests/test_crash_reconstruct.py::test_the_rear_end_from_rest_positions_alone_is_flagged_not_identifiable": 25,
    "tests/test_scene_examples.py::test_the_example_is_solved_at_seed_1_and_replays[billiards]": 23,
    "tests/test_docs.py::test_every_command_in_the_doc_runs[results/disks.md]": 17,
    "tests/test_docs.py::test_every_command_in_the_doc_runs[results/bowling.md]": 17,
    "tests/test_docs.py::test_every_command_in_the_doc_runs[crash.md]": 16,
}


_over_budget: list = []


def pytest_runtest_logreport(report):
    """Note the fast-tier tests that ran past FAST_TEST_S (setup, call and teardown together)."""
    if report.when == "call" and "slow" not in report.keywords and report.duration > FAST_TEST_S:
        _over_budget.append((report.duration, report.nodeid))


def pytest_terminal_summary(terminalreporter):
    """Name the fast-tier tests past the budget (the first test of a process may be compiling a
    kernel's test-only signature: a cold cache makes any test slow once)."""
    if _over_budget:
        terminalreporter.write_line(f"fast tier: {len(_over_budget)} test(s) took over {FAST_TEST_S:g} s: mark them "
                                    "@pytest.mark.slow (tests/conftest.py, 'the two tiers') unless a cold cache did it:")
        for d, nodeid in sorted(_over_budget, reverse=True)[:10]:
            terminalreporter.write_line(f"  {d:6.1f} s  {nodeid}")
