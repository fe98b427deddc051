"""Measured records of the L-panel study (``studies/l_panel.py``): the runs its docstring quotes
(``MEASURED``) and the quick l0 sweep (``L0_SWEEP``). Records of measurements, not inputs: no
value here sets a parameter. Forces in N for the whole 100 mm panel, loads in mm, W_f in N mm,
wall times in s."""

#: Measured with ngtmc.run_study on a shared, heavily loaded 2-core machine (wall times inflated).
#: Forces in N for the whole 100 mm panel; W_f (fracture_energy) in N mm for the whole panel.
#: ``crack_x_at_turning_point``: the smallest x (mm) with alpha > 0.9 in the snapshot at the turning point
#: (6.3 mm): the crack runs from the corner (x = 250 mm) to the left; the band ends at x = 150 mm.
MEASURED = {
    "quick": {"elements": 8516, "ndof_u": 8680, "ndof_alpha": 4340, "steps": 291, "newton_iterations": 660,
              "cutbacks": 4, "wall_time_s": 552, "first_loading_force_at_6.3": 17936,
              "force_first_loading_at_gap": 4765, "force_unloaded_at_gap": 4484, "wf_at_turning_point": 62.1,
              "unload_wf_lag": 4.83, "unload_wf_change_after_settle": 0.0, "reload_peak_force": 23621,
              "reload_peak_load": 6.46, "final_force": 8993},
    "quick_with_du_min_1e-8": {"note": "stopped at 6.536 mm after 459 steps (crack tail)",
                               "first_loading_force_at_6.3": 17935, "reload_peak_force": 22070,
                               "reload_peak_load": 6.378},
    "medium": {"elements": 27986, "ndof_u": 28204, "ndof_alpha": 14102, "steps": 1102, "newton_iterations": 2040,
               "cutbacks": 0, "wall_time_s": 2714, "linear_solve_time_s": 181, "first_loading_force_at_6.3": 18211,
               "force_first_loading_at_gap": 4574, "force_unloaded_at_gap": 4505, "wf_at_turning_point": 82.5,
               "unload_wf_lag": 17.5, "unload_wf_change_after_settle": 0.0, "reload_peak_force": 20843,
               "reload_peak_load": 6.35, "final_force": 7222, "status": "completed"},
    "quick_segment_loading": {"note": "--set load_introduction=segment: no indenter, no void (loads minus the gap)",
                              "elements": 7996, "steps": 160, "wall_time_s": 188, "first_loading_force_at_0.3": 18541,
                              "reload_peak_force": 24400, "reload_peak_load": 0.449},
    "quick_monotonic": {"note": "case monotonic, 0 -> 6.6 mm (one core, one thread)", "elements": 8516,
                        "steps": 198, "newton_iterations": 438, "wall_time_s": 65, "peak_force": 22962,
                        "peak_load": 6.451, "force_at_6.6": 17161, "drop_after_peak": 0.253},
    "medium_monotonic": {"note": "--set load_cases=monotonic --set monotonic_to=6.5, stopped at 6.3148 mm after the "
                                 "drop (crack running in steps of 1e-5 mm)", "elements": 27986, "steps": 238,
                         "wall_time_s": 216, "peak_force": 18632, "peak_load": 6.3106, "force_at_stop": 13675,
                         "status": "interrupted"},
    "quick_unload_single_pass": {"note": "--set load_cases=cyclic --set schedule=0,6.3,6,6.3", "steps": 153,
                                 "newton_iterations": 371, "wall_time_s": 55, "force_at_turning_point": 17936,
                                 "wf_at_turning_point": 62.10, "unload_wf_lag": 4.83, "max_alpha_after_lag": 0.4415,
                                 "force_unloaded_at_gap": 4484},
    "quick_path_following": {"note": "--set scheme=path-following, both cases (2026-11-25, two other jobs running)",
                             "monotonic_peak_force": 18445, "monotonic_peak_load": 6.302, "monotonic_steps": 155,
                             "monotonic_newton_iterations": 676, "main_steps": 169, "main_newton_iterations": 762,
                             "first_loading_peak_force": 18079, "reload_peak_force": 18598, "reload_peak_load": 6.311,
                             "wall_time_s": 535, "status": "completed"},
    "quick_path_following_no_ceiling": {"note": "ngtmc run l-panel --set scheme=path-following --workers 2, both "
                                                "cases (2026-12-02 evening): no growth ceiling, du_min 1e-6 mm, "
                                                "the fallback of displacement steps (docs/performance.md)",
                                        "main_steps": 152, "main_newton_iterations": 678, "main_cutbacks": 9,
                                        "reload_peak_force": 18597.5, "reload_peak_load": 6.3108,
                                        "monotonic_steps": 129, "monotonic_newton_iterations": 654,
                                        "monotonic_cutbacks": 13, "monotonic_peak_force": 18620.7,
                                        "monotonic_peak_load": 6.3064, "main_wall_time_s": 217,
                                        "monotonic_wall_time_s": 230, "status": "completed"},
    "quick_path_following_2026_12_02": {"note": "--set scheme=path-following --workers 2, both cases, idle machine "
                                                "(2026-12-02, commit 2333a3a). The monotonic case had failed at "
                                                "6.284 mm where its crack arrested (a bordered Newton step asking "
                                                "for a load change of 5e11 mm), since at least 2026-12-01; with "
                                                "ngtmc.stepping.path.LOAD_STEP_LIMIT (now rule 3 of ngtmc.stepping.path) it takes displacement steps there. "
                                                "Both cases with the final rule (commit dedeec6; monotonic alone, "
                                                "main beside another job). The rule's first version (commit "
                                                "2333a3a, --workers 2, 400 s): monotonic 368 steps, 1350 "
                                                "iterations; main 294 steps, 1077 iterations; the same forces",
                                        "monotonic_peak_force": 18621, "monotonic_peak_load": 6.3064,
                                        "monotonic_steps": 370, "monotonic_newton_iterations": 1242,
                                        "monotonic_cutbacks": 15, "monotonic_wall_time_s": 249,
                                        "monotonic_final_force": 9386, "main_steps": 294,
                                        "main_newton_iterations": 978, "main_cutbacks": 7, "main_wall_time_s": 181,
                                        "first_loading_force_at_6.3": 18079, "unload_wf_lag": 0.0,
                                        "reload_peak_force": 18598, "reload_peak_load": 6.3108, "main_final_force": 8309,
                                        "status": "completed"},
    "paper_single_pass_partial": {"note": "ngtmc run l-panel -r paper (the study's defaults: single-pass, Eq. 20, "
                                          "du_max 0.01 mm, du_min 1e-8 mm), one thread, one or two other jobs on the "
                                          "machine (2026-11-25); stopped in the crack run of the first loading at "
                                          "6.2854 mm after 874 steps, 1384 Newton iterations and 4738 s (about 850 s of it "
                                          "stopped with SIGSTOP while another run was timed): steps of "
                                          "1.6e-5..5e-5 mm, about a day to the end of the schedule at that pace",
                                  "elements": 102359, "ndof_u": 102710, "ndof_alpha": 51355, "steps": 874, "newton_iterations": 1384, "wall_time_s": 4738,
                                  "force_at_6.0": 5050, "first_loading_peak_force": 17257,
                                  "first_loading_peak_load": 6.274, "force_at_stop": 8354, "status": "interrupted"},
    "paper_path_following_partial": {"note": "ngtmc run l-panel -r paper --set scheme=path-following --workers 2 (both "
                                             "cases at once, one thread each, beside test and benchmark runs on the 2 "
                                             "cores: wall times are upper bounds), 2026-12-01; interrupted once and "
                                             "resumed (--resume), then stopped in the crack run (first stop below; "
                                             "resumed again on 2026-12-01 and stopped at the *_stop2 entries: 41 and "
                                             "37 more steps, crack about 47 mm long by the dissipated energy 419.6 N mm "
                                             "/ (Gc t), 5.2 N mm, about l0/2, per step on average). Each crack-run step "
                                             "dissipated one l0 of crack (W_f + 10.6 N mm = Gc l0 x 100 mm) in 4-6 Newton "
                                             "iterations and 35-80 s; two crack-run steps were cut back (34 and 22 iterations: "
                                             "at twice and at once that dissipation), so it stayed at one l0 or below",
                                     "elements": 102359, "ndof_u": 102710, "ndof_alpha": 51355, "setup_s": 106,
                                     "monotonic_steps": 79, "monotonic_newton_iterations": 320, "monotonic_cutbacks": 3,
                                     "monotonic_wall_time_s": 3141, "monotonic_peak_force": 15723,
                                     "monotonic_peak_load": 6.2417, "monotonic_force_at_stop": 13338,
                                     "monotonic_load_at_stop": 6.2197, "monotonic_wf_at_stop": 415.1,
                                     "main_steps": 69, "main_newton_iterations": 289, "main_cutbacks": 3,
                                     "main_wall_time_s": 3215, "first_loading_peak_force": 15746,
                                     "first_loading_peak_load": 6.2422, "main_force_at_stop": 13654,
                                     "main_load_at_stop": 6.2201, "status": "interrupted",
                                     "monotonic_steps_stop2": 120, "monotonic_newton_iterations_stop2": 546,
                                     "monotonic_cutbacks_stop2": 5, "monotonic_wall_time_s_stop2": 6694,
                                     "monotonic_load_at_stop2": 6.2117, "monotonic_force_at_stop2": 11525,
                                     "monotonic_dissipated_at_stop2": 419.6,
                                     "main_steps_stop2": 106, "main_newton_iterations_stop2": 524,
                                     "main_cutbacks_stop2": 6, "main_wall_time_s_stop2": 6781,
                                     "main_load_at_stop2": 6.2074, "main_force_at_stop2": 11489},
    "paper_path_following_2026_12_02": {"note": "ngtmc run l-panel -r paper --set scheme=path-following --workers 2, "
                                               "started 2026-12-02 and resumed across sessions (one or two threads, "
                                               "often beside other jobs); stopped in the crack run. Case main failed at "
                                               "step 193 (6.2078 mm) before the fixes of that night (docs/performance.md, "
                                               "'The paper L-panel's crawl'); the last hour (23:29-00:24, both cases on "
                                               "two workers): main steps 193-225 (596 Newton iterations, 16 cut-backs, "
                                               "3185 s), monotonic 151-184 (535, 20, 3248 s); then 00:37-01:04: main "
                                               "226-245 (310, 13, 1612 s), monotonic 185-204 (253, 8, 1514 s)",
                                       "elements": 102359, "ndof_u": 102710, "ndof_alpha": 51355,
                                       "first_loading_peak_force": 16006, "first_loading_peak_load": 6.2479,
                                       "monotonic_peak_force": 15729, "monotonic_peak_load": 6.2419,
                                       "main_steps": 245, "main_newton_iterations": 2134, "main_cutbacks": 59,
                                       "main_wall_time_s": 13515, "main_load_at_stop": 6.2114,
                                       "main_force_at_stop": 7518, "main_dissipated_at_stop": 1005.3,
                                       "monotonic_steps": 204, "monotonic_newton_iterations": 1590,
                                       "monotonic_cutbacks": 53, "monotonic_wall_time_s": 9757,
                                       "monotonic_load_at_stop": 6.2070, "monotonic_force_at_stop": 8381,
                                       "monotonic_dissipated_at_stop": 867.8, "status": "interrupted"},
    "paper_path_following_completed_2026_12_03": {
        "note": "the run above, resumed on 2026-12-03 with the weak-step stall and growth_ceiling='auto' "
                "(docs/performance.md) from main step 245 and monotonic step 204, completed (04:19-05:34, "
                "two workers, a third job on the two cores most of the time); case times accumulated over sessions",
        "elements": 102359, "ndof_u": 102710, "ndof_alpha": 51355,
        "main_steps": 361, "main_newton_iterations": 2760, "main_cutbacks": 73, "main_wall_time_s": 17134,
        "main_peak_memory_mb": 745, "first_loading_peak_force": 16006, "first_loading_peak_load": 6.2479,
        "force_at_turning_point": 6868, "force_first_loading_at_gap": 5312, "force_unloaded_at_gap": 2676,
        "reload_peak_force": 8830, "reload_peak_load": 6.6395, "final_force": 6752,
        "dissipated_at_turning_point": 1422.0, "dissipated_final": 4937.4,
        "monotonic_steps": 323, "monotonic_newton_iterations": 2314, "monotonic_cutbacks": 69,
        "monotonic_wall_time_s": 13954, "monotonic_peak_force": 15729, "monotonic_peak_load": 6.2419,
        "monotonic_final_force": 8790, "status": "completed"},
    "quick_turn_past_the_peak_2026_12_03": {
        "note": "ngtmc run l-panel --set load_cases=cyclic --set schedule=0,6.6,6,7 --set scheme=SCHEME --no-report "
                "(quick; the turning point past the first-loading peak, as at the paper's resolution), one after "
                "the other on one core beside another one-core job. Does the paper's single-pass scheme, whose "
                "damage lags one step and keeps growing in the first unloading steps, lower the reload peak?",
        "path_following": {"steps": 157, "newton_iterations": 775, "cutbacks": 14, "wall_time_s": 209,
                           "first_loading_peak_force": 18549, "first_loading_peak_load": 6.313,
                           "force_at_turning_point": 9380, "wf_at_turning_point": 5855.8, "unload_wf_growth": 0.0,
                           "force_unloaded_at_gap": 2420, "reload_peak_force": 9860, "reload_peak_load": 6.7746,
                           "final_force": 9458, "final_wf": 9908.6},
        "single_pass": {"steps": 348, "newton_iterations": 787, "cutbacks": 0, "wall_time_s": 110,
                        "first_loading_peak_force": 22962, "first_loading_peak_load": 6.451,
                        "force_at_turning_point": 17160, "wf_at_turning_point": 4695.0, "unload_wf_growth": 2121.9,
                        "force_unloaded_at_gap": 2640, "reload_peak_force": 10160, "reload_peak_load": 6.7968,
                        "final_force": 8814, "final_wf": 12380.1},
        "path_following_medium": {"note": "the same at --resolution medium (27986 elements, 28204 u dofs, "
                                          "h_band = 1 mm), beside the test suite",
                                  "steps": 274, "newton_iterations": 1173, "cutbacks": 15, "wall_time_s": 2833,
                                  "first_loading_peak_force": 16266, "first_loading_peak_load": 6.2641,
                                  "force_at_turning_point": 8414, "wf_at_turning_point": 5017.1,
                                  "unload_wf_growth": 0.0, "force_unloaded_at_gap": 2169,
                                  "reload_peak_force": 8439, "reload_peak_load": 6.6217,
                                  "final_force": 7975, "final_wf": 8790.9}},
    "medium_path_following_paper_schedule_2026_12_03": {
        "note": "ngtmc run l-panel -r medium --set load_cases=cyclic --set scheme=path-following --no-report "
                "--no-vtk (the paper's schedule 0 -> 6.3 -> 6 -> 7 mm; the crack runs before the turning point, "
                "as at the paper's resolution), one thread beside a two-thread 3D run for most of its time",
        "elements": 27986, "ndof_u": 28204, "ndof_alpha": 14102,
        "steps": 247, "newton_iterations": 1057, "cutbacks": 8, "wall_time_s": 3449,
        "first_loading_peak_force": 16843, "first_loading_peak_load": 6.2736,
        "force_at_turning_point": 6944, "wf_at_turning_point": 3258.7, "dissipated_at_turning_point": 1629.3,
        "unload_wf_growth": 0.0, "force_unloaded_at_gap": 2665, "reload_peak_force": 8679,
        "reload_peak_load": 6.4924, "final_force": 7977, "final_wf": 8840.0},
    "medium_path_following_paper_schedule_spectral_2026_12_04": {
        "note": "the same with --set split=spectral (Miehe's spectral split in the history, Ambati's), one thread, "
                "alone for most of its time",
        "elements": 27986, "ndof_u": 28204, "ndof_alpha": 14102,
        "steps": 298, "newton_iterations": 1243, "cutbacks": 15, "wall_time_s": 1911,
        "first_loading_peak_force": 16836, "first_loading_peak_load": 6.2731,
        "force_at_turning_point": 6936, "wf_at_turning_point": 3276.1, "dissipated_at_turning_point": 1638.1,
        "unload_wf_growth": 0.0, "force_unloaded_at_gap": 2663, "reload_peak_force": 8679,
        "reload_peak_load": 6.4911, "final_force": 8150, "final_wf": 8797.5},
    "medium_path_following_segment_2026_12_04": {
        "note": "ngtmc run l-panel -r medium --set scheme=path-following --set load_cases=cyclic --set "
                "load_introduction=segment (no indenter, no void: the schedule minus the 6 mm gap, 0 -> 0.3 -> 0 -> "
                "1.0 mm, imposed on the arm's lower face from x = 470 to 500 mm; loads below are those, add 6 mm "
                "to compare), one thread beside another job; stopped at 0.8929 mm (a step cut back for 8 minutes)",
        "elements": 27089, "ndof_u": 27288, "ndof_alpha": 13644,
        "steps": 248, "newton_iterations": 1233, "cutbacks": 20, "wall_time_s": 2217,
        "first_loading_peak_force": 17077, "first_loading_peak_load": 0.2779,
        "force_at_turning_point": 8042, "dissipated_at_turning_point": 1372.1, "unload_wf_growth": 0.1,
        "force_unloaded_at_gap": 0.0, "reload_peak_force": 9599, "reload_peak_load": 0.808,
        "dissipated_at_reload_peak": 3270.6, "force_at_stop": 9451, "load_at_stop": 0.8929},
    "medium_path_following_indenter_r10_2026_12_04": {
        "note": "the run of medium_path_following_paper_schedule_2026_12_03 with --set indenter_radius=10 (our 20 mm "
                "halved), one thread beside other jobs (paused for 18 minutes)",
        "elements": 27579, "ndof_u": 27788, "ndof_alpha": 13894,
        "steps": 304, "newton_iterations": 1304, "cutbacks": 17, "wall_time_s": 3007, "crack_x_at_turning_point": 149.1,
        "first_loading_peak_force": 16834, "first_loading_peak_load": 6.2643,
        "force_at_turning_point": 6911, "wf_at_turning_point": 3271.6, "dissipated_at_turning_point": 1635.8,
        "unload_wf_growth": 0.0, "force_unloaded_at_gap": 2343, "reload_peak_force": 8662,
        "reload_peak_load": 6.4894, "final_force": 7980, "final_wf": 8850.9},
    "medium_path_following_l0_2.375_2026_12_05": {
        "note": "the run of medium_path_following_paper_schedule_2026_12_03 with --set l0=2.375 (twice the study's "
                "1.1875 mm; the paper's l0 is not legible in its text), one thread beside a second run and other jobs",
        "l0": 2.375, "elements": 27986, "ndof_u": 28204, "ndof_alpha": 14102,
        "steps": 245, "newton_iterations": 1047, "cutbacks": 12, "wall_time_s": 3567,
        "first_loading_peak_force": 15267, "first_loading_peak_load": 6.2480,
        "force_at_turning_point": 6252, "wf_at_turning_point": 2968.8, "dissipated_at_turning_point": 1484.4,
        "crack_x_at_turning_point": 143.1,
        "unload_wf_growth": 0.0, "force_unloaded_at_gap": 2508, "reload_peak_force": 6405,
        "reload_peak_load": 6.3622, "final_force": 4241, "final_wf": 8643.9},
    "medium_path_following_l0_4.75_2026_12_05": {
        "note": "the same with --set l0=4.75 (4 x 1.1875 mm): on reloading the crack grows again at the turning "
                "point's force, and by 7 mm it has cut the panel (alpha > 0.9 from x = 0 to 250 mm)",
        "l0": 4.75, "elements": 27986, "ndof_u": 28204, "ndof_alpha": 14102,
        "steps": 223, "newton_iterations": 1073, "cutbacks": 15, "wall_time_s": 3688,
        "first_loading_peak_force": 13756, "first_loading_peak_load": 6.2283,
        "force_at_turning_point": 5089, "wf_at_turning_point": 3028.3, "dissipated_at_turning_point": 1514.2,
        "crack_x_at_turning_point": 133.6,
        "unload_wf_growth": 0.0, "force_unloaded_at_gap": 2221, "reload_peak_force": 5070,
        "reload_peak_load": 6.3040, "final_force": 91, "final_wf": 10575.8},
    "medium_path_following_band_left_100_2026_12_05": {
        "note": "the run of medium_path_following_paper_schedule_2026_12_03 with --set band_left=100 (the refined "
                "band from x = 100 instead of 150 mm), one thread, beside benchmarks and two CI runs (paused for "
                "18 minutes): the crack stops at the band's new end by the turning point",
        "band_left": 100.0, "elements": 39146, "ndof_u": 39364, "ndof_alpha": 19682,
        "steps": 357, "newton_iterations": 1561, "cutbacks": 22, "wall_time_s": 5976,
        "first_loading_peak_force": 16837, "first_loading_peak_load": 6.2736,
        "force_at_turning_point": 3541, "wf_at_turning_point": 4564.5, "dissipated_at_turning_point": 2282.3,
        "crack_x_at_turning_point": 100.0, "crack_x_at_7": 77.6,
        "unload_wf_growth": 0.0, "force_unloaded_at_gap": 1779, "reload_peak_force": 4341,
        "reload_peak_load": 6.9255, "final_force": 4274, "final_wf": 7013.9},
    "medium_path_following_band_left_0_2026_12_05": {
        "note": "the run of medium_path_following_paper_schedule_2026_12_03 with --set band_left=0 (the refined band "
                "over the whole width, x from 0 to 260 mm), one thread, stopped and resumed three times (wall_time_s "
                "is its clock, pauses for CI runs included): the crack runs through the panel's width before the turning "
                "point; on reloading the force only creeps up, no peak by 7 mm (reload_peak_force None, "
                "reload_largest_force at the end). crack_track: (step, load, force, dissipated, smallest x with "
                "alpha > 0.9) read from the checkpoint during the run (steps 421 and 429 from the snapshots)",
        "band_left": 0.0, "elements": 60268, "ndof_u": 60582, "ndof_alpha": 30291, "status": "finished",
        "steps": 429, "newton_iterations": 2037, "cutbacks": 30, "wall_time_s": 13640,
        "first_loading_peak_force": 16822, "first_loading_peak_load": 6.2736,
        "snap_back_lowest_load": 5.3109, "snap_back_lowest_load_step": 411,
        "force_at_turning_point": 98.8, "wf_at_turning_point": 7052.7, "dissipated_at_turning_point": 3526.3,
        "crack_x_at_turning_point": 4.3, "crack_x_at_7": 3.5,
        "unload_wf_growth": 0.0, "force_unloaded_at_gap": 94.9, "reload_peak_force": None,
        "reload_largest_force": 100.75, "reload_largest_force_load": 7.0, "final_wf": 7077.8,
        "crack_track": [(80, 6.2632, 14857, None, 238.2), (143, 6.2455, 10645, 785.5, 205.4),
                        (170, 6.2463, 9860, 920.7, 196.0), (187, 6.2500, 9277, 1037.4, 188.0),
                        (237, 6.2459, 8091, 1225.6, 175.0), (273, 6.2459, 6334, 1546.4, 151.5),
                        (298, 6.2506, 4331, 1960.0, 120.5), (317, 6.2565, 2870, 2320.5, 93.5),
                        (363, 6.1925, 943, 2935.6, 46.5), (380, 6.0974, 571, 3115.8, 32.9),
                        (397, 5.7552, 281, 3296.1, 20.8), (421, 6.3000, 98.8, 3526.3, 4.3),
                        (429, 7.0000, 100.75, 3538.9, 3.5)]},
    "quick_unload_monolithic": {"note": "the same with --set scheme=monolithic", "steps": 153,
                                "newton_iterations": 486, "wall_time_s": 84, "force_at_turning_point": 17908,
                                "wf_at_turning_point": 70.76, "unload_wf_lag": 0.0, "max_alpha_at_turning_point": 0.4827,
                                "force_unloaded_at_gap": 4483},
}

#: The l0 sweep (study docstring, "l0 sweep"): case ``monotonic`` (0 -> 6.6 mm) at quick, one run per
#: row, reproduced by L0_SWEEP_COMMAND with the row's l0 (and h_far where it differs from quick's
#: 25 mm). Forces in N for the whole 100 mm panel, loads in mm, wall time in s of the case on one
#: core (one thread). A measurement: no row was chosen to meet a reference.
L0_SWEEP_COMMAND = ("ngtmc run l-panel --resolution quick --set load_cases=monotonic --set l0={l0} "
                    "[--set h_far={h_far}] --no-report")
L0_SWEEP = [
    {"l0": 1.1875, "h_band": 2.0, "h_far": 25.0, "elements": 8516, "peak_force": 22962, "peak_load": 6.451,
     "force_at_6.6": 17161, "steps": 198, "wall_time_s": 65},
    {"l0": 4.75, "h_band": 2.0, "h_far": 25.0, "elements": 8516, "peak_force": 16413, "peak_load": 6.310,
     "force_at_6.6": 3824, "steps": 214, "wall_time_s": 67},
    {"l0": 12.0, "h_band": 2.0, "h_far": 25.0, "elements": 8516, "peak_force": 14061, "peak_load": 6.276,
     "force_at_6.6": 554, "steps": 221, "wall_time_s": 72},
    {"l0": 33.33, "h_band": 2.0, "h_far": 25.0, "elements": 8516, "peak_force": 11634, "peak_load": 6.259,
     "force_at_6.6": 32, "steps": 210, "wall_time_s": 66},
    {"l0": 33.33, "h_band": 2.0, "h_far": 8.0, "elements": 13845, "peak_force": 11554, "peak_load": 6.259,
     "force_at_6.6": 21, "steps": 212, "wall_time_s": 118},
]

#: The crack free to run (study docstring, "The refined band's end sets it"): the paper's schedule
#: (case main, 0 -> 6.3 -> 6 -> 7 mm), path following, one thread, with the refined band over the
#: whole width (``--set band_left=0``) and, as the same-resolution control, with the study's band
#: (from x = 150 mm). Reproduced by WHOLE_WIDTH_COMMAND with the row's resolution, l0 and band_left.
#: crack_x_at_turning_point: smallest x (mm) with alpha > 0.9 at 6.3 mm (the crack runs left from the
#: corner at x = 250 mm, the panel is 250 mm wide there). reload_peak_force None: on reloading the force only
#: creeps up (reload_largest_force, at 7 mm). crack_track of an unfinished run: (step, load, force,
#: dissipated, smallest x with alpha > 0.9) from its checkpoint during the run. Measured 2026-12-05
#: beside other runs on the 2 cores.
WHOLE_WIDTH_COMMAND = ("ngtmc run l-panel --resolution {resolution} --set load_cases=cyclic --set scheme=path-following "
                     "--set band_left={band_left} --set l0={l0} --no-report --no-vtk --threads 1")
_FREE = MEASURED["medium_path_following_band_left_0_2026_12_05"]
WHOLE_WIDTH = [
    {"l0": 1.1875, "resolution": "medium", "band_left": 0.0, "status": "finished",
     "record": "medium_path_following_band_left_0_2026_12_05",
     **{k: _FREE[k] for k in ("elements", "first_loading_peak_force", "first_loading_peak_load", "snap_back_lowest_load",
                              "crack_x_at_turning_point", "force_at_turning_point", "dissipated_at_turning_point",
                              "reload_peak_force", "reload_largest_force", "steps", "newton_iterations", "cutbacks",
                              "wall_time_s")}},
    {"l0": 2.375, "resolution": "quick", "band_left": 0.0, "status": "finished", "elements": 16780,
     "first_loading_peak_force": 15933, "first_loading_peak_load": 6.2666, "snap_back_lowest_load": 5.035,
     "crack_x_at_turning_point": 5.2, "force_at_turning_point": 74.5, "dissipated_at_turning_point": 3514.8,
     "reload_peak_force": None, "reload_largest_force": 77.1, "steps": 270, "newton_iterations": 1164,
     "cutbacks": 12, "wall_time_s": 1340},
    {"l0": 4.75, "resolution": "quick", "band_left": 0.0, "status": "finished", "elements": 16780,
     "first_loading_peak_force": 14327, "first_loading_peak_load": 6.2427, "snap_back_lowest_load": 4.805,
     "crack_x_at_turning_point": 5.2, "force_at_turning_point": 72.4, "dissipated_at_turning_point": 2976.9,
     "reload_peak_force": None, "reload_largest_force": 75.6, "steps": 236, "newton_iterations": 1102,
     "cutbacks": 30, "wall_time_s": 1833},
    {"l0": 4.75, "resolution": "quick", "band_left": 150.0, "status": "finished", "elements": 8516,
     "first_loading_peak_force": 14356, "first_loading_peak_load": 6.2429, "snap_back_lowest_load": None,
     "crack_x_at_turning_point": 140.7, "force_at_turning_point": 5474, "dissipated_at_turning_point": 1586.7,
     "reload_peak_force": 5476, "reload_peak_load": 6.3156, "final_force": 80, "crack_x_at_7": 0.0, "steps": 201,
     "newton_iterations": 832, "cutbacks": 11, "wall_time_s": 478},
    {"l0": 4.75, "resolution": "medium", "band_left": 0.0, "elements": 60268,
     "status": "unfinished: stopped for time at step 279 (5.8838 mm, 0.46 kN, crack to x = 36.3 mm), before the "
               "turning point; 1348 Newton iterations, 15 cut-backs, 6509 s (resumable)",
     "first_loading_peak_force": 13733, "first_loading_peak_load": 6.2281,
     "crack_track": [(96, 6.2000, 9224, 549.1, 211.7), (122, 6.2013, 7375, 835.4, 185.9),
                     (152, 6.2041, 5983, 1074.0, 163.9), (193, 6.2043, 4222, 1397.4, 134.0),
                     (208, 6.2038, 3698, 1503.5, 124.0), (249, 6.1631, 1378, 2070.8, 69.5),
                     (279, 5.8838, 459, 2415.4, 36.3)]},
    {"l0": 12.0, "resolution": "quick", "band_left": 0.0, "elements": 16780,
     "status": "stalled at 6.1785 mm (2.58 kN, crack to x = 110.8 mm, 1656.6 N mm dissipated): steps of 1e-6 "
               "mm with up to 66 Newton iterations and 12 cut-backs; stopped at step 138 (807 Newton iterations, "
               "32 cut-backs, 1631 s)",
     "first_loading_peak_force": 12797, "first_loading_peak_load": 6.2243},
]
