"""L-shaped panel, load - unload - reload through an indenter: irreversibility of the crack.

What this study shows
---------------------
The second validation of Ciceri et al. (2026), Sect. "L-shaped panel irreversibility": the
Winkler (2001) L-shaped concrete panel is loaded upward near the end of its horizontal arm by a
solid semicircular indenter that starts 6 mm (l_h) below it, across a third-medium void. The
imposed indenter displacement goes 0 -> 6.3 -> 6 -> 7 mm (load past the peak, unload back to the
contact point, reload). A crack starts at the re-entrant corner. What must be seen:

1. while the indenter crosses the gap the force stays small (the void, gamma0 = 1e-6, only
   stiffens as it is squeezed);
2. first loading: the panel is loaded through the squeezed void, a crack starts at the corner and
   the force peaks;
3. unloading to u = l_h: **no crack growth** (max alpha and W_f constant: the history variable
   H_n = max(H_{n-1}, Psi_plus) keeps alpha from healing and unloading does not raise Psi_plus), and
   the force returns to its first-loading value at u = l_h (about zero);
4. reloading: softer (the crack is there), up to a **lower peak**, 7.6 kN in the paper.

Two cases (``load_cases``): ``main``, the paper's load-unload-reload schedule above, and
``monotonic``, 0 -> ``monotonic_to`` = 6.6 mm, which goes past the first-loading peak (the paper's
first loading ends at 6.3 mm, before the peak of this model at quick) and is compared with the
first-loading peak of Ambati et al. 2015. ``--set load_cases=monotonic`` runs it alone (the l0
sweep below).

Geometry (mm; the paper's Fig. 12 is not available, sizes it does not give are our choices)
-------------------------------------------------------------------------------------------
* panel: 500 x 500 square without the lower-right 250 x 250 quadrant (Winkler); the bottom edge
  of the vertical leg (y = 0, x in [0, 250]) is clamped (x and y). Plane strain, thickness 100 mm
  (the Winkler specimen's), so forces are for the whole panel, in N: directly comparable with the
  paper's 7.6 kN and with the Winkler band (kN, whole specimen);
* fracture is modelled in the whole panel except a strip ``clamp_strip`` = 25 mm high along the
  clamped edge (paper: "we restrict fracture in the indenter and near the fixed edge"), except
  the indenter, and **except the contact zone** x in [430, 500] x y in [250, 270] of the arm above
  the indenter (our addition). Without that exclusion the contact pressure under the indenter
  (Psi_dev drives AT-2 damage under compression with the J-split, see MODEL.md) crushed the arm
  locally: in a quick run the force dropped from 17.8 kN to 2.4 kN at u = 6.296 mm with a crack
  energy of only 2.9 N mm/mm (about 9 mm of crack), and every reloading punched through again
  (5 kN peaks). Winkler loaded the arm through a steel plate, so the load introduction is not part
  of the fracture problem. The void (rho = 0) has no phase field;
* indenter: solid half disc, radius ``indenter_radius`` = 20 mm (our choice), flat side down,
  centred under x = ``load_x`` = 470 mm (30 mm from the arm's right end, Winkler's load point),
  its apex ``gap`` = 6 mm below the arm's lower face (y = 250). Same material as the panel, no
  fracture. Its flat bottom edge is the loaded boundary: the upward displacement is imposed there,
  the tangential one held (hold_tangential, a floating indenter in a soft void otherwise has a
  near-singular rigid mode); the recorded force is the vertical reaction there;
* void (rho = 0): the box x in [load_x - R - 10, 500], y from the indenter's flat edge to the arm's
  lower face, minus the indenter. No regulariser (paper: "no regularisation energy is introduced
  in the void domain"), so linear triangles (displacement order 1) throughout, as the paper;
* mesh: refined band x in [150, 260] x y in [230, 320] (``h_band``; ``band_left`` moves its left end) around the expected crack path
  (from the corner at (250, 250) to the left and slightly up, Winkler's experiments and Ambati et
  al. 2015), contact zone x in [430, 500] x y in [250, 270] in the arm (``h_contact``), void and
  indenter ``h_void``, the rest ``h_far``.

Parameters and sources
----------------------
Table 2 of the paper: E0 = 2.58e4 MPa, nu = 0.18, Gc = 8.93e-5 kN/mm = 0.0893 N/mm,
gamma0 = 1e-6. l0 is not legible in the paper's text: l0 = 1.1875 mm (Ambati et al. 2015, who
also used h = 0.5 mm in the cracking region, as the paper). Schedule 0 -> 6.3 -> 6 -> 7 mm,
l_h = 6 mm, k_u = 50 (paper). **k_u is in 1/N with W_f per unit thickness** (N mm/mm), the
convention of :class:`ngtmc.AdaptiveStepControl`: with the 100 mm thickness, W_f in the history
(whole panel, N mm) is 100 times the W_f that enters Eq. 20. Residual stiffness 1e-6 (at least
gamma0, MODEL.md).

Resolutions change mesh and step sizes only: ``quick`` (CI: h_band = 2 mm, i.e. 1.7 l0 > l0/2,
so the solver's ResolutionWarning is expected and accepted for speed: the crack is smeared over a
few elements and the phase field overestimates the dissipated energy, by about 1 + h/(2 l0);
and a step floor du_min = 5e-3 mm: with the paper's 1e-8 the running crack takes hundreds of
steps of 1e-8 .. 1e-3 mm, more than 450 steps to reach 6.54 mm), ``medium`` (h_band = 1 mm,
du_min = 1e-8), ``paper`` (h_band = 0.5 mm as the paper, du_max = 0.01 mm, du_min = 1e-8; long).

Expected result (paper)
-----------------------
Force about zero until the void is squeezed near u = 6 mm; first peak, then at u = 6.3 mm the
crack has started; unloading: alpha and W_f constant, force back to its first-loading value at
u = 6 mm; reloading softer with a lower peak, 7.6 kN in the paper. Winkler's experimental band
(peak 6.7 - 7.6 kN at 0.2 mm) is shown shifted by the gap.

Measured (forces for the whole 100 mm panel; details in ``MEASURED``)
----------------------------------------------------------------------
* Irreversibility holds: once the load has dropped 0.075 mm below the turning point, W_f and max
  alpha stay constant to the last digit until reloading passes 6.3 mm again, and the reloading
  curve retraces the unloading one. Damage does grow in the first unloading steps (W_f +7.8 % at
  quick, +21 % at medium, within 0.06 mm of the turning point): the single-pass scheme lags damage
  by one step and the tiny first unloading steps (Eq. 20 after a fast W_f increase) still apply the
  damage driven by the last loading states. The monolithic scheme removes the lag (quick,
  ``--set load_cases=cyclic --set schedule=0,6.3,6,6.3``, with ``--set scheme=monolithic`` or
  without): W_f does not change once unloading starts (0.0 against +4.83 N mm, +7.8 %, single-pass),
  W_f at the turning point is 70.76 N mm against 62.10 (single-pass, 66.93 after its lag) and max
  alpha 0.483 against 0.412 (0.442); the forces hardly move (17.91 against 17.94 kN at 6.3 mm, 4.48
  against 4.48 kN unloaded at 6 mm); 153 steps each, 486 against 371 Newton iterations, 84 against
  55 s. The single-pass scheme's damage at the turning point is thus 12 % low, 5.4 % low after its lag.
* **Path following removes most of the quick peak's excess** (``--set scheme=path-following``,
  2026-11-25, both cases, 535 s on a machine running two other jobs): the monotonic case peaks at
  **18.45 kN at 6.302 mm** (155 steps, 676 Newton iterations), against 22.96 kN at 6.451 mm with
  the single-pass scheme at the same quick mesh and 18.63 kN at medium: the +23 % of the quick
  single-pass peak was its one-step damage lag on the 0.05 mm steps, not the mesh. The cycle
  (main case) completes in 169 steps and 762 iterations; its first loading reaches 18.08 kN and
  the reload peak is 18.60 kN at 6.311 mm (single-pass: 23.62 kN). Against Ambati's 16 kN the
  converged quick peak is +15.3 %, just outside the ±15 % of the test (still an expected failure).
  Measured again on 2026-12-02 (``MEASURED["quick_path_following_2026_12_02"]``): the main case
  is the same (18.08 kN at 6.3 mm, reload peak 18.60 kN at 6.311 mm, no W_f growth on
  unloading) in 294 steps and 978 iterations; the monotonic case samples its peak at 18.62 kN
  at 6.306 mm (370 steps, 1242 iterations, 249 s alone). The monotonic case had failed where its
  crack arrests (6.284 mm, 10.3 kN): the bordered Newton step of a dissipation step asked for a
  load change of 5e11 mm, since the damage no longer responds to the load, and inverted
  elements at every line-search length; the last attempt of such a step is now a displacement
  step (rule 3 of ``ngtmc.stepping.path``). Both cases take about twice the steps of 2026-11-25:
  the cause is the ceiling on the growth of the dissipation step after a cut-back (commit
  32c1e15: 155 -> 283 steps, 677 -> 1048 iterations, the same peak), which holds the crack run's
  steps small; switched off on today's code, the run stalls at 6.2986 mm instead
  (docs/performance.md, "Which change doubled the quick L-panel's steps"). Since the evening of
  2026-12-02 path following's displacement steps fall back to staggered passes where the coupled
  Newton stalls, and the study runs path following without the ceiling and with du_min at most
  1e-6 mm (``_options``, ``PATH_FOLLOWING_DU_MIN``): quick, monotonic 126 steps and 868
  iterations (peak 18.62 kN at 6.306 mm), cyclic 152 steps and 678 iterations (reload peak
  18.60 kN at 6.311 mm), the same peaks.
* At u = l_h the force is 4.8 kN on first loading (not "about zero": the third medium between the
  curved indenter and the arm is squeezed over some 20 mm and carries load from about 5.8 mm on;
  approach-only runs gave F(6.0) = 5.4 kN with 2.5 mm void elements and 4.8 kN with 0.5 mm ones at
  the apex), 4.5 kN after unloading (quick -5.9 %, medium -1.5 %): the same within the stiffness
  lost to the damage.
* Not reproduced at quick and medium (at the paper's resolution the first loading passes its
  peak before 6.3 mm and the reload peak is 8.83 kN, +16 %: section "Reload peak at the paper's
  resolution" below): the panel is far stronger than in the paper. At 6.3 mm the first loading has not
  peaked (17.9 kN quick, 18.2 kN medium, diffuse damage, max alpha 0.41 / 0.67: the monotonic case
  peaks at 6.451 mm at quick and at 6.311 mm at medium, below); the crack runs
  on reloading from 23.6 kN (quick, 6.46 mm) / 20.8 kN (medium, 6.35 mm), against 7.6 kN
  (+211 % / +174 %). The contact is not the cause: the diagnostic variant
  ``--set load_introduction=segment`` (no indenter, no void, the displacement minus the gap imposed
  on the arm's lower face from x = 470 to 500 mm) gives the same picture at quick, 18.5 kN at
  0.3 mm and a reload peak of 24.4 kN at 0.45 mm (188 s). The mesh is not the cause either: the
  reload peak falls from quick to medium as the phase-field toughness overestimate
  Gc (1 + h / (2 l0)) does (h_band 2 -> 1 mm: factor 1.84 -> 1.42, force ratio sqrt = 1.14,
  measured 1.13); extrapolated to h -> 0 that gives about 17.5 kN, still 2.3 times the paper's.
  What remains is the fracture model with these parameters: the AT-2 strength
  3 sqrt(3)/16 sqrt(E Gc / l0) = 14.3 MPa is five times concrete's (Winkler: about 2.7 MPa), and
  the same model reproduces the three-point bending peak within 10 %. The paper's set-up details
  that could explain 7.6 kN (its l0 is not legible, its figures are missing) are not in its text.
  No parameter was tuned to the reference.
* Without excluding the contact zone from fracture the arm was crushed under the indenter (see
  the geometry section).

First-loading peak against Ambati et al. 2015 (case ``monotonic``)
-------------------------------------------------------------------
* Ambati et al. 2015 (Comput. Mech. 55, Fig. 19) compute this panel with the same AT-2 parameters
  (l0 = 1.1875 mm, h = 0.5 mm) and load the arm directly; a public reimplementation reads their
  first-loading peak as about 16 kN. **Thickness reading: 16 kN for the whole 100 mm panel** (the
  Winkler specimen's thickness, the thickness of this study). The other reading, 16 kN per mm of
  thickness, is ruled out by the numbers: with the same parameters this model carries 0.23 kN per
  mm (22.96 kN / 100 mm), 70 times less, and the experiments carry 0.07 kN per mm. Only the force
  is compared: Ambati's displacement has no gap.
* Measured at quick (l0 = 1.1875 mm): the monotonic case peaks at **22.96 kN at u = 6.451 mm**
  (198 steps, 65 s on one core), then drops to 17.2 kN at 6.6 mm (-25 %, max alpha 1, the crack
  runs from the corner). Against Ambati's 16 kN: **+43.5 %, outside ±15 %** (a strict expected
  failure of EXPECTED, with this value). The reload peak of case ``main`` (23.6 kN at 6.46 mm) is
  the same peak, 2.9 % higher: unloading from 6.3 mm, before the peak, leaves the strength alone.
  Quick does not resolve l0 (h_band = 2 mm = 1.7 l0; toughness overestimate 1 + h/(2 l0) = 1.84).
  At medium (h_band = 1 mm = 0.84 l0, still above l0/2; ``--resolution medium --set
  load_cases=monotonic --set monotonic_to=6.5``, 27986 elements) the peak is **18.63 kN at 6.311
  mm, +16.4 %** against Ambati's 16 kN, just outside ±15 %; the drop follows at once (13.67 kN at
  6.3148 mm, -27 %, after 238 steps and 216 s, where the run was stopped: the running crack takes
  steps of 1e-5 mm). The peak falls by 19 % from quick to medium, more than the sqrt of the
  toughness factors (1.84 -> 1.42: 12 %). Extrapolated to h -> 0 it lies between 14.3 kN (linear
  in h) and 15.6 kN (medium divided by sqrt(1.42)), -11 % to -2 % against Ambati, who used h = 0.5
  mm = 0.42 l0: the first-loading peak is consistent with Ambati's once the mesh resolves l0.
* Those quick and medium peaks are the single-pass scheme's, which lags damage by one step. With
  path following (no lag) the first-loading peak is 18.62 kN at 6.306 mm at quick
  (``MEASURED["quick_path_following_2026_12_02"]``), **16.27-16.84 kN at medium (+1.7 % to +5.3 %
  against Ambati's 16 kN**; 2026-12-03, two cyclic runs, turning points 6.6 and 6.3 mm, whose
  first loadings follow the same path but whose path-following steps, bounded by 1/50 of the
  load path, sample the sharp peak differently: ``MEASURED["quick_turn_past_the_peak_2026_12_03"]``
  and ``MEASURED["medium_path_following_paper_schedule_2026_12_03"]``) and 15.73-16.01 kN at the
  paper's resolution (below).
* **Measured at the paper's resolution** (h_band = 0.5 mm, 102359 elements, 102710 u and 51355
  alpha dofs; ``ngtmc run l-panel -r paper --set scheme=path-following --workers 2``, 2026-12-01,
  ``MEASURED["paper_path_following_partial"]``): the first-loading peak is **15.72 kN at 6.242 mm**
  in case ``monotonic`` and 15.75 kN at 6.242 mm in case ``main`` (the same peak, sampled by other
  displacement steps), **-1.7 % against Ambati's 16 kN**, inside the estimate above. The paper's
  single-pass scheme on the same mesh peaked at 17.26 kN at 6.274 mm (a stopped run,
  ``MEASURED["paper_single_pass_partial"]``): its
  one-step damage lag puts it 9.8 % above the path-following peak, which has no lag (the peak
  is sampled by displacement steps of about 0.036 mm; the next step, a dissipation step, went
  back to 6.240 mm, so the limit point lies there). Both runs were stopped in the crack
  run (see MEASURED), so the paper-resolution reload peak was not measured then. A second run from the
  start (2026-12-02, ``MEASURED["paper_path_following_2026_12_02"]``, resumed across sessions)
  peaks at 16.01 kN at 6.248 mm in case main (+0.1 % against Ambati's 16 kN) and 15.73 kN at
  6.242 mm in case monotonic; both passed stalls in the crack run near 6.208 mm (a residual floor
  of the displacement Newton, a dissipation predictor tied to the cut-back step, the step
  control's slow recovery: fixed, docs/performance.md) and **completed on 2026-12-03**: case main
  in 361 steps, 2760 Newton iterations, 73 cut-backs, no staggered pass (17134 s of case time,
  accumulated over several sessions, mostly beside other jobs; 745 MB), case monotonic in 323
  steps, 2314 iterations, 69 cut-backs (13954 s).

Reload peak at the paper's resolution (case ``main``, completed 2026-12-03)
----------------------------------------------------------------------------
* The first loading passes its peak (16.01 kN at 6.248 mm) before the turning point (6.3 mm), as
  in the paper; the crack runs from the corner at about 6.21 mm while the force falls to 6.1 kN
  (dissipated energy 1323 N mm, about 148 mm of crack by D / (Gc t)), then the arm is carried by
  the contact again: 6.87 kN at 6.3 mm, 2.68 kN after unloading to 6.0 mm (first loading there:
  5.31 kN).
* **Reload peak 8.83 kN at 6.640 mm, +16.2 % against the paper's 7.6 kN**, just outside ±15 %
  (the test at quick stays a strict expected failure). After it the force falls to 6.75 kN at
  7.0 mm while the dissipated energy grows from 1.42 to 4.94 kN mm. Case monotonic ends at
  8.79 kN at 6.6 mm.
* So the 7.6 kN of the paper is the reload peak of a **cracked** panel. At quick and medium the
  first loading stops before the peak (it lies at 6.451 and 6.311 mm), so their "reload peak"
  (23.6 and 20.8 kN) is the first peak of the uncracked panel: a different quantity, not a
  +211 % error of the model. What is left is +16 % at l0 = 1.1875 mm, the paper's own mesh size,
  with the refined band ending at x = 150 mm; with the band from x = 100 mm the crack runs 50 mm
  further and the reload peak is 4.34 kN, -43 % (bullet "The refined band's end sets it" below).
* **The paper's scheme does not explain the +16 %** (measured 2026-12-03,
  ``MEASURED["quick_turn_past_the_peak_2026_12_03"]``). The paper solves each step once with the
  history of the step before (single-pass); its damage lags and keeps growing while the load
  falls, which could lengthen the crack before reloading and so lower the reload peak. Tested at
  quick with the turning point past the first-loading peak, as at the paper's resolution
  (``--set load_cases=cyclic --set schedule=0,6.6,6,7``), once per scheme, and with path following
  at medium:

  ===============================  ===============  ===============  ===============
  turning point 6.6 mm              quick,           quick,           medium,
                                    path following   single-pass      path following
  ===============================  ===============  ===============  ===============
  first-loading peak                18.55 kN         22.96 kN         16.27 kN
  force at the turning point        9.38 kN          17.16 kN         8.41 kN
  W_f at the turning point          5856 N mm        4695 N mm        5017 N mm
  W_f growth while unloading        0                +2122 N mm       0
                                                     (+45 %)
  **reload peak**                   **9.86 kN**      **10.16 kN**     **8.44 kN**
  force at 7 mm                     9.46 kN          8.81 kN          7.97 kN
  steps, Newton iterations          157, 775         348, 787         274, 1173
  ===============================  ===============  ===============  ===============

  The single-pass crack catches up while unloading (its W_f ends 16 % above path following's at
  6.0 mm), yet its reload peak is 3 % *higher*, not lower. So the scheme moves the reload peak by
  a few per cent, in the wrong direction to explain the paper's 7.6 kN. Not measured: the
  single-pass scheme at the paper's resolution (hours), where the crack run and the turning
  point are the paper's.
* **The mesh does not explain it either** (measured 2026-12-03,
  ``MEASURED["medium_path_following_paper_schedule_2026_12_03"]``). With the paper's own schedule
  at medium (h_band = 1 mm, path following; the crack runs before the turning point there too):
  force at the turning point 6.94 kN (paper resolution: 6.87 kN), dissipated energy there 1629
  N mm (1422), **reload peak 8.68 kN at 6.492 mm against 8.83 kN at 6.640 mm at the paper's
  resolution**: halving the band's elements moves it by +1.7 %, so it is converged to a few per
  cent and stays 14-16 % above 7.6 kN. (With the turning point at 6.6 mm the reload peak fell by
  14.4 % from quick to medium, 9.86 to 8.44 kN, about the square root of the toughness factors
  1 + h/(2 l0), 12.2 %: quick is too coarse there, medium is not.)
* **The split does not explain it either** (measured 2026-12-04,
  ``MEASURED["medium_path_following_paper_schedule_spectral_2026_12_04"]``): the same medium run
  with Miehe's spectral split in the history (``--set split=spectral``, Ambati's choice) gives
  a first-loading peak of 16.84 kN (-0.04 %), 6.94 kN at the turning point, 1638 N mm dissipated
  there (+0.5 %) and a **reload peak of 8.679 kN at 6.491 mm, the same as with the J-based
  vol-dev split to four digits** (8.679 kN at 6.492 mm); 298 steps, 1243 Newton iterations, 1911 s.
* **The load introduction moves it, upward** (measured 2026-12-04,
  ``MEASURED["medium_path_following_segment_2026_12_04"]``): the same medium run with ``--set
  load_introduction=segment`` (no indenter, no void; the schedule minus the 6 mm gap imposed on
  the arm's lower face over its last 30 mm; loads below plus 6 mm): first-loading peak 17.08 kN
  at 6.278 mm (+1.4 % against the indenter's 16.84 kN), 8.04 kN at the turning point (indenter:
  6.94 kN) with 1372 N mm dissipated (1629 N mm: a shorter crack). On reloading the crack grows
  again from the turning point on, at a slowly rising force: its largest force is **9.60 kN at
  6.808 mm, +10.6 % against the indenter's 8.68 kN** (+26 % against 7.6 kN); the run was stopped
  at 6.893 mm (9.45 kN, a step cut back for minutes). So the indenter and the void lower the
  reload peak by about 10 % against a held segment.
* **The indenter's radius does not move it** (measured 2026-12-04,
  ``MEASURED["medium_path_following_indenter_r10_2026_12_04"]``; the radius, 20 mm, is our
  choice, the paper's figure is missing): with ``--set indenter_radius=10`` the same medium run
  peaks at 16.83 kN at 6.264 mm on first loading (-0.05 %), has 6.91 kN and 1636 N mm dissipated
  at the turning point (6.94 kN, 1629 N mm), and **reloads to 8.662 kN at 6.489 mm, -0.2 %**
  against 8.679 kN; 304 steps, 1304 Newton iterations, 3007 s.
* **The length scale l0 moves it most** (measured 2026-12-05,
  ``MEASURED["medium_path_following_l0_2.375_2026_12_05"]`` and ``..._l0_4.75_...``; the paper's
  l0 is not legible in its text, 1.1875 mm is Ambati's): the same medium run with ``--set l0=2.375``
  and ``--set l0=4.75`` (the report's figure "Reload peak against l0")::

      l0 (mm)  first-loading peak  at turning point  dissipated there  crack to x  reload peak
      1.1875   16.84 kN            6.94 kN           1629 N mm         149 mm      8.68 kN at 6.492 mm
      2.375    15.27 (-9.3 %)      6.25              1484              143         6.41 at 6.362 (-26.2 %)
      4.75     13.76 (-18.3 %)     5.09              1514              134         5.07 at 6.304 (-41.6 %)

  (crack to x: the smallest x with alpha > 0.9 at the turning point, the crack running left from
  the corner at x = 250 mm; for 1.1875 mm from the run with half the indenter's radius, which
  reloads the same.) The cracks at the turning point are about as long, yet the reload peak falls
  three times faster with l0 than the first-loading peak, and at 4.75 mm the crack grows again at
  the turning point's force. The paper's 7.6 kN lies between 1.1875 and 2.375 mm (about 1.6 mm by
  log-linear interpolation, where the first-loading peak would be about 16.1 kN). So, with this
  band, an l0 about a third larger than Ambati's would explain the paper's reload peak; this is a
  measured sensitivity, not a fit: the study keeps l0 = 1.1875 mm. 245 and 223 steps, 1047 and 1073 Newton
  iterations, 3567 and 3688 s (two runs side by side). But at the turning point every one of these
  cracks ends near the band's left end (x = 150 mm), which the next bullet shows to be no accident.
* **The refined band's end sets it** (measured 2026-12-05,
  ``MEASURED["medium_path_following_band_left_100_2026_12_05"]``): the same medium run (l0 =
  1.1875 mm) with ``--set band_left=100``, the band from x = 100 instead of 150 mm (39146 instead
  of 27986 elements). Up to about 1000 N mm dissipated the two runs agree (9.34 against 9.33 kN);
  the first-loading peak is the same, 16.84 kN at 6.274 mm. Then the band's run turns: its load
  rises from 6.257 to 6.3 mm while its crack slows down at the band's end, where the elements grow
  (at 250 < y < 290 mm the longest edges average 1.0 mm at x = 150-170 mm, 2.4 mm at 140-150 mm
  and 8.6 mm at 120-140 mm, so the effective toughness Gc (1 + h/(2 l0)) grows by 1.4x to 4.6x).
  The wider band's crack runs on at about 6.25 mm, 50 mm further, and stops at its band's end
  too::

      band from x  at turning point  dissipated there  crack to x  reload peak
      150 mm       6.94 kN           1629 N mm         149 mm      8.68 kN at 6.492 mm
      100 mm       3.54 kN           2282 N mm         100.0 mm    4.34 kN at 6.926 mm (-50 %)

  (crack to x as in the table above; by 7 mm the wider band's crack reaches x = 77.6 mm, into
  the coarse mesh.) So the crack's length at the turning point, and with it the reload peak, is
  set by where the refined band ends, a choice of the mesh, not by the model: at l0 = 1.1875 mm a
  crack resolved further would run further and reload lower still. The paper's 7.6 kN lies
  between the two bands. The agreement of medium and the paper's resolution (8.68 and 8.83 kN)
  comes from their common band, and the l0 sweep above is conditional on it too. 357 steps, 1561
  Newton iterations, 22 cut-backs, 5976 s.
  **With the band over the whole width** (``--set band_left=0``, 60268 elements;
  ``MEASURED["medium_path_following_band_left_0_2026_12_05"]``, measured 2026-12-05) the first
  loading is the same (16.82 kN at 6.274 mm), and the crack does not stop: it passes x = 150 mm
  at 6.246 mm (6.3 kN) and x = 100 mm at about 6.256 mm (2.9 kN), then the load snaps back while
  it runs on (x = 32.9 mm at 6.097 mm and 0.57 kN, 20.8 mm at 5.755 mm and 0.28 kN), down to
  5.311 mm, and rises again with the panel broken in two: at the turning point the crack reaches x = 4.3
  mm of the 250 mm width, 98.8 N are left (3526 N mm dissipated), and on reloading the force only
  creeps up, to 100.8 N at 7 mm (x = 3.5 mm): **no reload peak**. So at l0 = 1.1875 mm, with the
  crack resolved wherever it runs, the panel breaks through before 6.3 mm, and every reload peak
  of the study (8.68 kN at medium, 8.83 kN at the paper's resolution, 4.34 kN with the band from
  x = 100 mm) is the restart of a crack that the band's end arrested. 429 steps, 2037 Newton
  iterations, 30 cut-backs, 13640 s on its clock (stopped and resumed three times).
  **The same at larger l0** (``WHOLE_WIDTH``, measured 2026-12-05, path following, the paper's
  schedule; quick has h_band = 2 mm over the whole width, 16780 elements)::

      l0 (mm)  resolution  band          first-loading peak  crack at 6.3 mm to x  force at 6.3 mm  reload peak
      1.1875   medium      whole width   16.82 kN            4.3 mm                98.8 N           none
      2.375    quick       whole width   15.93               5.2                   74.5 N           none
      4.75     quick       whole width   14.33               5.2                   72.4 N           none
      4.75     quick       x >= 150      14.36               140.7                 5.47 kN          5.48 kN at 6.316 mm

  (none: on reloading the force only creeps up, by at most 5 % by 7 mm.) At each l0 the crack
  free to run crosses the panel while the load snaps back (to 5.31, 5.03 and 4.80 mm), and
  the same quick run with the study's band, the control, reaches the same first-loading peak
  (+0.2 %) but stops its crack 9 mm past the band's end and reloads to 5.48 kN, restarting at
  the turning point's force as at medium. At l0 = 12 mm (quick, whole width) the run stalled at
  6.1785 mm with its crack at x = 110.8 mm (2.58 kN; steps of 1e-6 mm). The medium run at
  l0 = 4.75 mm (whole width, 60268 elements; stopped for time at step 279) peaks at 13.73 kN
  (the band's run: 13.76 kN); its crack passes x = 134 mm, where the band's crack stood at the
  turning point, at 6.204 mm and 4.22 kN, and runs on to x = 36.3 mm while the load snaps back to
  5.884 mm (0.46 kN), as at l0 = 1.1875 mm. **So for l0 from 1.1875 to 4.75 mm this model has no
  arrested crack at 6.3 mm when the crack is resolved wherever it runs**: the paper's reload
  peak of 7.6 kN, like ours, needs a crack stopped by its mesh; it is not a property of the
  model at these l0. The paper's text does not say how far its refined zone reaches.
* At the paper's resolution the reload peak is 28.6 % above the force at the turning point (8.83
  against 6.87 kN; 25.0 % at medium with the same schedule; at quick and medium with the turning
  point at 6.6 mm, 5.1 % and 0.3 %): there the crack had arrested by 6.3 mm and restarts at
  6.49-6.64 mm, where at 6.6 mm it was still running. So what is left of the +16 % is neither the
  scheme, the element size, the split nor the indenter's radius, and loading the arm without the
  indenter raises the reload peak rather than lowering it; the extent of the refined band is
  what moves it (the bullet "The refined band's end sets it").
  A longer crack at the turning point would lower that restart force; what sets its length in the
  paper's run is not in its text. The report shows these reload peaks in
  its figure "Reload peak of the cracked panel".

l0 sweep (case ``monotonic``, quick; ``L0_SWEEP``)
---------------------------------------------------
AT-2's homogeneous strength 3 sqrt(3)/16 sqrt(E Gc / l0) equals concrete's sigma_t = 2.7 MPa at
l0 = 27 E Gc / (256 sigma_t^2) = 27 * 25800 * 0.0893 / (256 * 2.7^2) = **33.33 mm** (34.4 mm with
the plane-strain E / (1 - nu^2)). Swept: today's 1.1875 mm, 4.75 mm (4 x) and 12 mm between,
and 33.33 mm; each run ``ngtmc run l-panel --resolution quick --set load_cases=monotonic
--set l0=L0 --no-report`` (the last row adds ``--set h_far=8``), one at a time on one core. Forces
for the whole 100 mm panel::

    l0 (mm)  strength  h_band  h_band/l0  h_far  elements  peak (kN)  at u (mm)  F(6.6 mm)  steps  wall (s)
    1.1875   14.3 MPa  2 mm    1.68       25 mm   8516     22.96      6.451      17.2 kN    198     65
    4.75      7.15     2       0.42       25      8516     16.41      6.310       3.8       214     67
    12        4.50     2       0.17       25      8516     14.06      6.276       0.55      221     72
    33.33     2.70     2       0.06       25      8516     11.63      6.259       0.03      210     66
    33.33     2.70     2       0.06        8     13845     11.55      6.259       0.02       212    118

* **No l0 reaches Winkler's 6.7-7.6 kN band**: the peak falls from 22.96 kN to 11.63 kN as l0 grows
  28-fold, and at the l0 that gives AT-2 concrete's strength it is still 53 % above 7.6 kN. The
  peak falls far slower than 1/sqrt(l0) (that would give 4.3 kN at 33.33 mm): the earlier estimate
  "l0 of about 5-12 mm reaches 7.6 kN" does not hold. l0 = 4.75 mm comes within 3 % of Ambati's
  16 kN, but Ambati used 1.1875 mm: not a match of that reference.
* Up to 6.1 mm the curves of all l0 agree within 5 % (4.7-4.8 kN at 6.0 mm, 7.7-8.1 kN at 6.1 mm:
  the squeezed void and the nearly elastic panel); they part as the damage at the corner grows
  (10.8-12.8 kN at 6.2 mm), and the peak moves from 6.451 mm to 6.259 mm.
* Mesh. The band (x 150-260, y 230-320, h_band = 2 mm) resolves l0 >= 4 mm (h <= l0/2); l0 =
  1.1875 mm is not resolved (h = 1.7 l0, the largest toughness overestimate, 1.84 against 1.21,
  1.08, 1.03), so its peak is the least reliable and too high. For the large l0 the damage leaves
  the band: at 6.30 mm, just past the peak of l0 = 33.33 mm, alpha reaches 0.86 just below the
  band at the corner and exceeds 0.5 from x = 184 to 257 mm; after the peak the crack runs out of
  the band (x < 150 mm) for every l0 >= 4.75 mm (l0 = 1.1875 mm: alpha > 0.5 reaches x = 176 mm
  by 6.6 mm). The far mesh (h_far = 25 mm, 0.75 l0 at l0 = 33.33 mm) does not set the peak: with
  h_far = 8 mm (l0/4) the peak is 11.55 kN, -0.7 %, at the same displacement.
"""
from __future__ import annotations

from functools import partial

import numpy as np

import ngtmc
from ngtmc.simulation import peak_index
from ngtmc.study import data_path
from ngtmc.study import Case
from ngtmc.study import SOLVER_PARAMETERS, simulation_options
from ngtmc.studies._l_panel_geometry import (_segment, build_mesh, effective_gap,  # noqa: F401 (interface)
                                            effective_schedule)
from ngtmc.studies._l_panel_measured import (L0_SWEEP, L0_SWEEP_COMMAND, MEASURED,  # noqa: F401 (records)
                                             WHOLE_WIDTH, WHOLE_WIDTH_COMMAND)

NAME = "l_panel"
TITLE = "L-shaped panel: load, unload, reload through an indenter"
SUMMARY = (
    "Winkler's L-shaped panel (500 x 500 mm without a 250 x 250 quadrant, 100 mm thick, Table 2 of "
    "Ciceri et al. 2026) is pushed upward near the end of its arm by a semicircular indenter that starts "
    "6 mm away across a third-medium void (gamma0 = 1e-6, no regulariser, linear triangles). Schedule "
    "0 -> 6.3 -> 6 -> 7 mm: a crack starts at the re-entrant corner on first loading, does not grow while "
    "unloading (irreversibility), and the reloading is softer with a lower peak (paper: 7.6 kN). The Winkler "
    "experimental band is shown shifted by the gap."
)

#: Parameters added after runs of this study were recorded, at the default those runs had in
#: effect (``band_left``: the band from x = 150 mm): left out of the parameter hash at that default,
#: so that those runs still resume (:func:`ngtmc.study.registry.added_at_default`).
ADDED_AT_DEFAULT = ("band_left",)

PARAMETERS = {
    "E": (2.58e4, "MPa", "Young's modulus E0 (Table 2)"),
    "nu": (0.18, "-", "Poisson's ratio (Table 2)"),
    "Gc": (0.0893, "N/mm", "critical energy release rate, 8.93e-5 kN/mm (Table 2)"),
    "l0": (1.1875, "mm", "phase-field length scale (Ambati et al. 2015; not legible in the paper)"),
    "gamma0": (1e-6, "-", "void stiffness ratio of Eq. 17 (Table 2)"),
    "residual_stiffness": (1e-6, "-", "added to g(alpha); at least about gamma0 (MODEL.md)"),
    "thickness": (100.0, "mm", "out-of-plane thickness: the Winkler panel (forces for the whole panel, N)"),
    "gap": (6.0, "mm", "gap l_h between indenter apex and the arm's lower face (paper)"),
    "schedule": ([0.0, 6.3, 6.0, 7.0], "mm", "imposed indenter displacement: load, unload to l_h, reload (paper)"),
    "load_x": (470.0, "mm", "x of the indenter axis, 30 mm from the arm's right end (Winkler)"),
    "indenter_radius": (20.0, "mm", "radius of the semicircular indenter (our choice)"),
    "void_margin": (10.0, "mm", "void box extends this far left of the indenter (our choice)"),
    "band_left": (150.0, "mm", "left end of the refined band (x from band_left to 260 mm, y from 230 to 320 mm; "
                  "our choice, around the expected crack path)"),
    "clamp_strip": (25.0, "mm", "height of the strip along the clamped edge without fracture (our choice)"),
    "k_u": (50.0, "1/N", "step-size sensitivity of Eq. 20, W_f per unit thickness (paper: 50)"),
    **SOLVER_PARAMETERS,
    "load_cases": ("both", "-", "'both' (the paper's load-unload-reload case 'main' and the monotonic case 'monotonic'), "
                   "'cyclic' (case 'main' only) or 'monotonic' (case 'monotonic' only, as in the l0 sweep)"),
    "monotonic_to": (6.6, "mm", "end of the monotonic case 'monotonic' (0 -> monotonic_to): past the first-loading "
                     "peak, which the paper's first loading (to 6.3 mm) does not reach at quick"),
    "load_introduction": ("indenter", "-", "'indenter' (paper: an indenter pushes the arm across a 6 mm void) or "
                          "'segment' (diagnostic: no indenter and no void; the schedule minus the gap is imposed on "
                          "the arm's lower face from load_x to its end)"),
    "split": ("vol-dev-J", "-", "tension/compression split (ngtmc.model.splits.SPLITS): 'vol-dev-J' (paper), "
              "'vol-dev-small', 'vol-dev-log', 'spectral' (Miehe 2010; Ambati's history) or 'none'"),
    "formulation": ("hybrid", "-", "where the split acts: 'hybrid' (history only; paper) or 'anisotropic'"),
}

RESOLUTIONS = {
    "quick": {"h_band": 2.0, "h_contact": 2.5, "h_void": 2.5, "h_far": 25.0, "du_max": 0.05, "du_min": 0.005},
    "medium": {"h_band": 1.0, "h_contact": 1.5, "h_void": 2.0, "h_far": 20.0, "du_max": 0.05, "du_min": 1e-8},
    "paper": {"h_band": 0.5, "h_contact": 1.0, "h_void": 1.0, "h_far": 15.0, "du_max": 0.01, "du_min": 1e-8},
}
RESOLUTION_PARAMETERS = {
    "h_band": ("mm", "element size in the refined band along the crack path"),
    "h_contact": ("mm", "element size in the arm above the indenter"),
    "h_void": ("mm", "element size in the void and the indenter"),
    "h_far": ("mm", "element size elsewhere in the panel"),
    "du_max": ("mm", "largest load increment (Eq. 20)"),
    "du_min": ("mm", "floor of Eq. 20 and smallest increment on cut-back (paper, three-point bending: 1e-8); under "
                      "path following at most 1e-6 (the floor of its cut-backs only)"),
}
DEFAULT_RESOLUTION = "quick"

#: Winkler's experimental peak band (whole 100 mm panel, N): the paper's 7.6 kN is its upper bound.
WINKLER_PEAK_BAND = (6700.0, 7600.0)
#: Concrete's tensile strength (Winkler), MPa: the strength l0_for_strength matches in the sweep.
SIGMA_T = 2.7


def at2_strength(E: float, Gc: float, l0: float) -> float:
    """Homogeneous (1D) strength of AT-2, MPa: 3 sqrt(3)/16 sqrt(E Gc / l0) (E in MPa, Gc in N/mm,
    l0 in mm)."""
    return 3.0 * np.sqrt(3.0) / 16.0 * np.sqrt(E * Gc / l0)


def l0_for_strength(E: float, Gc: float, sigma: float) -> float:
    """The l0 (mm) at which AT-2's homogeneous strength is ``sigma`` (MPa): 27 E Gc / (256 sigma^2)."""
    return 27.0 * E * Gc / (256.0 * sigma ** 2)


def figures(p: dict) -> list[dict]:
    """The report's figures of recorded runs: the l0 sweep (L0_SWEEP, quick, far mesh of quick:
    peaks against l0, with Winkler's band and Ambati's first-loading peak), the reload peaks of a
    cracked panel (:func:`_reload_figure`) and the reload peak against l0 at medium
    (:func:`_reload_l0_figure`)."""
    rows = [r for r in L0_SWEEP if r["h_far"] == 25.0]
    l0s = [r["l0"] for r in rows]
    x = [min(l0s) / 1.2, max(l0s) * 1.2]
    return [{
        "title": "First-loading peak against l0 (recorded l0 sweep, quick)",
        "x_title": "phase-field length l0 (mm)", "y_title": "peak force (N, whole 100 mm panel)", "x_log": True,
        "caption": ("Peak force of the monotonic case against l0, measured at quick (h_band = 2 mm, so l0 = "
                    "1.1875 mm is not resolved: h = 1.7 l0) with the commands of the study docstring; recorded "
                    "data of the study, not computed in this run. l0 = 33.33 mm gives AT-2 the strength 2.7 MPa "
                    "of concrete. At l0 = 1.1875 mm, also the medium mesh's peaks: the single-pass scheme's (its "
                    "damage lags one step) and path following's (two runs). Look for: whether any l0 reaches Winkler's "
                    "6.7-7.6 kN band (none does); path following at medium 2-5 % above Ambati's 16 kN."),
        "series": [
            {"label": "this model, monotonic peak (quick)", "kind": "curve", "x": l0s,
             "y": [r["peak_force"] for r in rows]},
            {"label": "Winkler experiments, peak band 6.7-7.6 kN", "kind": "band", "x": x,
             "y_lower": [WINKLER_PEAK_BAND[0]] * 2, "y_upper": [WINKLER_PEAK_BAND[1]] * 2},
            {"label": "Ambati et al. 2015, Fig. 19: about 16 kN at l0 = 1.1875 mm", "kind": "points",
             "x": [1.1875], "y": [16000.0]},
            {"label": "this model, monotonic peak at medium (h_band = 1 mm), single-pass", "kind": "points",
             "x": [1.1875], "y": [float(MEASURED["medium_monotonic"]["peak_force"])]},
            {"label": "this model, first-loading peak at medium, path following (no damage lag)", "kind": "points",
             "x": [1.1875, 1.1875],
             "y": [float(MEASURED["quick_turn_past_the_peak_2026_12_03"]["path_following_medium"]
                         ["first_loading_peak_force"]),
                   float(MEASURED["medium_path_following_paper_schedule_2026_12_03"]["first_loading_peak_force"])]},
        ],
    }, _reload_figure(), _reload_l0_figure()]


#: the recorded medium runs with the paper's schedule and path following, by l0 (mm)
MEDIUM_PAPER_SCHEDULE_BY_L0 = {1.1875: "medium_path_following_paper_schedule_2026_12_03",
                               2.375: "medium_path_following_l0_2.375_2026_12_05",
                               4.75: "medium_path_following_l0_4.75_2026_12_05"}


def _whole_width_by_resolution() -> dict:
    """The finished WHOLE_WIDTH runs with the band over the whole width, by resolution (medium first)."""
    out: dict = {}
    for res in ("medium", "quick", "paper"):
        rows = sorted((r for r in WHOLE_WIDTH if r["resolution"] == res and r["band_left"] == 0.0
                       and r["status"] == "finished"), key=lambda r: r["l0"])
        if rows:
            out[res] = rows
    return out


def _reload_l0_figure() -> dict:
    """The report's figure of the recorded first-loading and reload peaks against l0 at medium with
    the paper's schedule (path following), against the paper's 7.6 kN."""
    l0s = sorted(MEDIUM_PAPER_SCHEDULE_BY_L0)
    rec = [MEASURED[MEDIUM_PAPER_SCHEDULE_BY_L0[l0]] for l0 in l0s]
    wide = MEASURED["medium_path_following_band_left_100_2026_12_05"]
    quick_band = sorted((r for r in WHOLE_WIDTH if r["band_left"] > 0 and r["status"] == "finished"),
                        key=lambda r: r["l0"])
    x = [l0s[0] / 1.2, l0s[-1] * 1.2]
    return {
        "title": "Reload peak against l0 (recorded runs, medium, the paper's schedule)",
        "x_title": "phase-field length l0 (mm)", "y_title": "force (N, whole 100 mm panel)", "x_log": True,
        "caption": ("First-loading and reload peaks of the case main (0 -> 6.3 -> 6 -> 7 mm) at medium (h_band = "
                    "1 mm) with path following, for the study's l0 = 1.1875 mm and twice and four times it "
                    "(--set l0=...; the paper's l0 is not legible in its text); recorded data of the study, not "
                    "computed in this run. Look for: the reload peak falls much faster with l0 than the first-loading "
                    "peak (-26 % against -9 % from 1.1875 to 2.375 mm), and the paper's 7.6 kN lies between the "
                    "two smaller l0; at 4.75 mm the crack grows again at the turning point's force, with no reload "
                    "peak above it. But every one of these cracks stops near the refined band's end (x = 150 mm) "
                    "by the turning point: with the band from x = 100 mm (--set band_left=100, l0 = 1.1875 mm) "
                    "the crack stops at x = 100 mm and the reload peak halves, 4.34 kN (the single point), so "
                    "these reload peaks are set by the band's extent, a choice of the mesh. With the band over the "
                    "whole width (--set band_left=0) the crack runs through the panel's width before the turning "
                    "point at every l0 whose run finished, and the panel reloads to no peak: those points are the "
                    "force left at 6.3 mm (below 0.1 kN); at quick the study's band reloads the same l0 to 5.48 kN "
                    "(the control)."),
        "series": [
            {"label": "first-loading peak (medium, path following)", "kind": "curve", "x": l0s,
             "y": [float(r["first_loading_peak_force"]) for r in rec]},
            {"label": "reload peak (medium, path following)", "kind": "curve", "x": l0s,
             "y": [float(r["reload_peak_force"]) for r in rec]},
            {"label": "force at the turning point, 6.3 mm", "kind": "points", "x": l0s,
             "y": [float(r["force_at_turning_point"]) for r in rec]},
            {"label": "reload peak with the band from x = 100 mm (medium, path following)", "kind": "points",
             "x": [l0s[0]], "y": [float(wide["reload_peak_force"])]},
            *[{"label": f"force at the turning point, band over the whole width ({res}): the crack through the "
                        "panel's width, no reload peak", "kind": "points", "x": [r["l0"] for r in rows],
               "y": [float(r["force_at_turning_point"]) for r in rows]}
              for res, rows in _whole_width_by_resolution().items()],
            {"label": "reload peak with the study's band, quick (the same-resolution control)", "kind": "points",
             "x": [r["l0"] for r in quick_band], "y": [float(r["reload_peak_force"]) for r in quick_band]},
            {"label": "Ciceri et al. 2026: reload peak 7.6 kN", "kind": "curve", "x": x, "y": [7600.0, 7600.0]},
        ],
    }


def _reload_figure() -> dict:
    """The report's figure of the recorded reload peaks of a cracked panel (turning point past the
    first-loading peak): path following and the paper's single-pass scheme at quick, path following
    at the paper's resolution, against the paper's 7.6 kN."""
    turn = MEASURED["quick_turn_past_the_peak_2026_12_03"]
    paper = MEASURED["paper_path_following_completed_2026_12_03"]
    x = [6.55, 6.85]
    return {
        "title": "Reload peak of the cracked panel (recorded runs)",
        "x_title": "indenter displacement at the reload peak (mm)", "y_title": "reload peak (N, whole 100 mm panel)",
        "caption": ("Reload peaks of runs whose first loading passed its peak before the turning point, so that "
                    "the panel reloads with a crack: at quick with the turning point at 6.6 mm (--set "
                    "load_cases=cyclic --set schedule=0,6.6,6,7), path following and the paper's single-pass "
                    "scheme, at medium (path following), and with the paper's turning point 6.3 mm at medium and at "
                    "the paper's resolution (path following). Recorded data "
                    "of the study, not computed in this run. Look for: the single-pass scheme, whose damage keeps "
                    "growing while unloading (+45 % W_f at quick), reloads 3 % higher than path following, not "
                    "lower: the scheme does not explain the paper's 7.6 kN; nor does the mesh: with the paper's turning "
                    "point, medium and the paper's resolution agree within 2 %; nor does the split: the spectral split "
                    "reloads to the same 8.679 kN at medium as the J-based vol-dev split."),
        "series": [
            {"label": "path following, quick (turning point 6.6 mm)", "kind": "points",
             "x": [turn["path_following"]["reload_peak_load"]], "y": [float(turn["path_following"]["reload_peak_force"])]},
            {"label": "single-pass (paper's scheme), quick (turning point 6.6 mm)", "kind": "points",
             "x": [turn["single_pass"]["reload_peak_load"]], "y": [float(turn["single_pass"]["reload_peak_force"])]},
            {"label": "path following, medium (turning point 6.6 mm)", "kind": "points",
             "x": [turn["path_following_medium"]["reload_peak_load"]],
             "y": [float(turn["path_following_medium"]["reload_peak_force"])]},
            {"label": "path following, medium (turning point 6.3 mm)", "kind": "points",
             "x": [MEASURED["medium_path_following_paper_schedule_2026_12_03"]["reload_peak_load"]],
             "y": [float(MEASURED["medium_path_following_paper_schedule_2026_12_03"]["reload_peak_force"])]},
            {"label": "path following, medium, spectral split (turning point 6.3 mm)", "kind": "points",
             "x": [MEASURED["medium_path_following_paper_schedule_spectral_2026_12_04"]["reload_peak_load"]],
             "y": [float(MEASURED["medium_path_following_paper_schedule_spectral_2026_12_04"]["reload_peak_force"])]},
            {"label": "path following, paper resolution (turning point 6.3 mm)", "kind": "points",
             "x": [paper["reload_peak_load"]], "y": [float(paper["reload_peak_force"])]},
            {"label": "Ciceri et al. 2026: reload peak 7.6 kN (displacement not given)", "kind": "curve", "x": x,
             "y": [7600.0, 7600.0]},
        ],
    }


REGIONS = "band|contact_zone|clamp_strip|panel|indenter|void"
FRACTURE_REGIONS = ["band", "panel"]


def build_scene(p: dict) -> ngtmc.Scene:
    mat = ngtmc.Material(E=float(p["E"]), nu=float(p["nu"]), Gc=float(p["Gc"]), l0=float(p["l0"]))
    if _segment(p):
        return ngtmc.Scene(
            mesh=build_mesh(p), materials={"band|contact_zone|clamp_strip|panel": mat},
            supports=[ngtmc.Support("clamp", x=True, y=True)],
            load=ngtmc.DisplacementLoad("load", direction="y"),
            fracture_regions=FRACTURE_REGIONS, regulariser=None,
            residual_stiffness=float(p["residual_stiffness"]), thickness=float(p["thickness"]), order=1,
            name="l_panel_segment", **_split(p))
    return ngtmc.Scene(
        mesh=build_mesh(p),
        materials={REGIONS: mat},
        supports=[ngtmc.Support("clamp", x=True, y=True)],
        load=ngtmc.DisplacementLoad("load", direction="y", hold_tangential=True),
        density={"void": 0.0},
        fracture_regions=FRACTURE_REGIONS,
        regulariser=None,
        gamma0=float(p["gamma0"]),
        residual_stiffness=float(p["residual_stiffness"]),
        thickness=float(p["thickness"]),
        order=1,
        name="l_panel",
        **_split(p),
    )


def _split(p: dict) -> dict:
    """The scene's energy split and formulation (``ngtmc.Scene`` checks them)."""
    return dict(split=str(p.get("split", PARAMETERS["split"][0])),
                formulation=str(p.get("formulation", PARAMETERS["formulation"][0])))


LOAD_CASES = {"both": ("main", "monotonic"), "cyclic": ("main",), "monotonic": ("monotonic",)}


def _load_cases(p: dict) -> tuple:
    mode = str(p.get("load_cases", "both"))
    if mode not in LOAD_CASES:
        raise ValueError(f"l_panel: load_cases = {mode!r} is not one of {', '.join(map(repr, LOAD_CASES))}")
    return LOAD_CASES[mode]


#: du_min under path following, mm, at most: there dissipation sets the steps of the crack run,
#: and du_min is only the floor of the cut-backs of a step. The quick resolution's 0.005 mm (a
#: floor for the single-pass scheme's Eq. 20) allowed three halvings of a dissipation step: the
#: cyclic case without the growth ceiling failed at 6.468 mm; with 1e-6 it completes (measured
#: 2026-12-02, docs/performance.md).
PATH_FOLLOWING_DU_MIN = 1e-6

def _options(p: dict) -> dict:
    """Simulation options of both cases: the solver settings. Under path following the ceiling on
    the growth of the dissipation per step after a cut-back is ngtmc's default, ``"auto"``
    (:meth:`ngtmc.stepping.sizing.DissipationSizing.ceiling_applies`): off at quick, where the crack path's
    elements (a median longest edge of 2.6 mm, 2.2 l0) are larger than CEILING_MAX_H = 1.5 l0 and
    a step of one l0 of crack is a fraction of an element (quick, case monotonic: 121 steps and 610
    Newton iterations without it, 207 and 1124 with it; the cyclic case 152 and 678 without it, 294
    and 978 with it before the ceiling's easy recovery); on at medium (1 mm band; since 2026-12-03;
    case monotonic has no cut-back, so the same 608 steps and 1245 iterations with or without it) and at the paper's resolution (0.5 mm, l0/2.4), where its crack run failed a step of
    one l0 in about half the attempts and went on at half of it in 5-8 iterations per step
    (docs/performance.md). Where a stall would still fail a step, its last attempt is a
    displacement step with staggered passes (path following's fallback); the quick run of both
    cases needed none."""
    return simulation_options(p)


def cases(p: dict) -> list[Case]:
    """Case ``main``: the paper's schedule 0 -> 6.3 -> 6 -> 7 mm; case ``monotonic``: 0 ->
    ``monotonic_to`` (past the first-loading peak). ``load_cases`` selects them."""
    du_max = float(p["du_max"])
    shift = float(p["gap"]) - effective_gap(p)
    du_min = min(float(p["du_min"]), du_max)
    if p.get("scheme", SOLVER_PARAMETERS["scheme"][0]) == "path-following":   # the floor of its cut-backs only (see _options)
        du_min = min(du_min, PATH_FOLLOWING_DU_MIN)
    # (under path following the scale doubles after every successful step: ngtmc.stepping.path.N_S)
    control = ngtmc.AdaptiveStepControl(du_max=du_max, k_u=float(p["k_u"]), du_min=du_min)
    which = _load_cases(p)
    out = []
    if "main" in which:
        out.append(Case(
            name="main", label=f"this model (k_u = {float(p['k_u']):g} 1/N, du_max = {du_max:g} mm)",
            scene=partial(build_scene, dict(p)),
            schedule=ngtmc.Schedule(effective_schedule(p)),
            control=control,
            options=_options(p),
            snapshot_loads=[x - shift for x in (5.9, 6.1, 6.2, 6.3, 7.0) if x - shift >= 0],
            parameters={"k_u": float(p["k_u"]), "du_max": du_max},
        ))
    if "monotonic" in which:
        end = float(p["monotonic_to"]) - shift
        if not end > 0:
            raise ValueError(f"l_panel: monotonic_to = {p['monotonic_to']!r} mm does not go past the gap")
        out.append(Case(
            name="monotonic", label=f"monotonic to {float(p['monotonic_to']):g} mm (l0 = {float(p['l0']):g} mm)",
            scene=partial(build_scene, dict(p)),
            schedule=ngtmc.Schedule([0.0, end]),
            control=control,
            options=_options(p),
            snapshot_loads=[x - shift for x in (6.1, 6.3, 6.45) if 0 <= x - shift < end] + [end],
            parameters={"k_u": float(p["k_u"]), "du_max": du_max, "l0": float(p["l0"])},
        ))
    return out


WINKLER_BAND_SOURCE = ("Winkler L-shaped panel experiments, scatter band (Winkler et al. 2004 IJNAMG Fig. 10 and "
                       "Winkler et al. 2001 Fig. 5), digitised; file from github fpled/MYCODE, examples/phasefield/"
                       "dataLshapedPanelWinkler/force_displacement_Win04_fig10_Win01_fig5.csv @ 626a87f0")
WINKLER_A_SOURCE = ("Winkler PhD thesis (2001), Abb. 7.12, test series A; file from github PSAAPGroupLinder/"
                    "lShapedPanelBenchmark, experimental/Winkler_Abb-7.12_Versuchsreihe-A.csv @ 70a51eeb")


def references(p: dict) -> list[dict]:
    """Winkler band and series A (whole 100 mm panel, N), shifted by the gap, scaled to the scene
    thickness (thickness / 100 mm)."""
    import pandas as pd
    gap = effective_gap(p)
    scale = float(p["thickness"]) / 100.0
    band = pd.read_csv(data_path("lshape_winkler_experiment_envelope_kN_mm.csv"))
    a = pd.read_csv(data_path("lshape_winkler_experiment_seriesA_N_mm.csv"))
    unit = "N" if scale == 1.0 else f"N per {float(p['thickness']):g} mm"
    return [
        {"label": "Winkler experiments, scatter band (shifted by the gap)", "source": WINKLER_BAND_SOURCE,
         "kind": "band", "x": (band["U_mm"] + gap).tolist(), "y_lower": (1000 * scale * band["F_lb_kN"]).tolist(),
         "y_upper": (1000 * scale * band["F_ub_kN"]).tolist(), "x_unit": "mm", "y_unit": unit},
        {"label": "Winkler series A (shifted by the gap)", "source": WINKLER_A_SOURCE, "kind": "curve",
         "x": (a["#x"] + gap).tolist(), "y": (scale * a["Winkel-A"]).tolist(), "x_unit": "mm", "y_unit": unit},
    ]


AMBATI_SOURCE = ("Ambati et al. 2015 (Comput. Mech. 55), Fig. 19, L-shaped panel with the same AT-2 parameters: "
                 "first-loading peak about 16 kN, read as the whole 100 mm panel (see the study docstring)")


def targets(p: dict) -> list[dict]:
    scale = float(p["thickness"]) / 100.0
    out = []
    if "main" in _load_cases(p):
        out.append({"case": "main", "quantity": "reload_peak_force", "value": 7600.0 * scale, "unit": "N",
                    "source": "Ciceri et al. 2026, L-panel text: reload peak 7.6 kN (whole 100 mm panel)",
                    "tolerance": 0.15})
    if "monotonic" in _load_cases(p):
        out.append({"case": "monotonic", "quantity": "peak_force", "value": 16000.0 * scale, "unit": "N",
                    "source": AMBATI_SOURCE, "tolerance": 0.15})
    return out


#: What the quick run (the CI run of tests/test_study_l_panel.py) is checked against, one record per
#: number (docs/study-interface.md): the quantity of metadata.json results (post_results: the
#: numbers of :func:`phases`), the value with its unit (N, whole 100 mm panel), tolerance (rel:
#: relative) and source. The published reload peak is not met (strict expected failure, with the
#: measured values); the measured quick values guard against regressions.
EXPECTED = {
    "reload_peak_force_published": {
        "case": "main", "quantity": "reload_peak_force", "value": 7600.0, "unit": "N", "rel": 0.15,
        "source": "Ciceri et al. 2026, L-panel text: reload peak 7.6 kN (whole 100 mm panel)",
        "xfail": "quick: reload peak measured 23.6 kN against the paper's 7.6 kN (+211 %); medium 20.8 kN "
                 "(+174 %): their first loading stops before the peak, so this is the uncracked panel's peak; "
                 "at the paper's resolution, where the crack runs before the turning point as in the paper, "
                 "8.83 kN at 6.640 mm (+16.2 %, path following, 2026-12-03; see the study); not the paper's "
                 "single-pass scheme: at quick with the turning point past the peak it reloads to 10.16 kN "
                 "against path following's 9.86 kN (+3 %); the element size does not move it (the paper's schedule "
                 "at medium reloads to 8.68 kN, against 8.83 kN at the paper's resolution), the refined band's "
                 "extent does: the crack stops at the band's end (x = 150 mm) by the turning point, and with the "
                 "band from x = 100 mm it stops there and reloads to 4.34 kN (-43 %; medium, 2026-12-05); with "
                 "the band over the whole width the crack runs through the panel's width (to x = 4.3 of 250 mm) "
                 "before 6.3 mm, with 98.8 N left, and reloading finds no peak (100.8 N at 7 mm; medium, 2026-12-05), and so it "
                 "does at l0 = 2.375 and 4.75 mm (quick), where the study's band reloads to 5.48 kN (WHOLE_WIDTH): "
                 "the published reload peak needs a crack arrested by its mesh"},
    "first_peak_force": {"case": "main", "quantity": "first_peak_force", "value": 17935.0, "unit": "N", "rel": 0.05,
                         "source": "measured, quick (regression guard; the turning point, 6.3 mm)"},
    "reload_peak_force": {"case": "main", "quantity": "reload_peak_force", "value": 23621.0, "unit": "N", "rel": 0.05,
                          "source": "measured, quick (regression guard)"},
    "force_first_loading_at_gap": {"case": "main", "quantity": "force_first_loading_at_gap", "value": 4765.0,
                                   "unit": "N", "rel": 0.05, "source": "measured, quick (regression guard)"},
    "monotonic_peak_force_ambati": {
        "case": "monotonic", "quantity": "peak_force", "value": 16000.0, "unit": "N", "rel": 0.15,
        "source": AMBATI_SOURCE,
        "xfail": "quick: monotonic peak measured 22.96 kN at 6.451 mm against Ambati's about 16 kN (+43.5 %); "
                 "h_band = 2 mm = 1.7 l0 overestimates the toughness by 1 + h/(2 l0) = 1.84; medium (h_band = 1 mm) "
                 "18.63 kN (+16.4 %), extrapolated to h -> 0 about 14.3-15.6 kN; with path following (no damage lag) "
                 "16.27-16.84 kN at medium (+1.7 to +5.3 %) and 15.72 kN at the paper's resolution (-1.7 %, see the study)"},
    "monotonic_peak_force": {"case": "monotonic", "quantity": "peak_force", "value": 22962.0, "unit": "N", "rel": 0.05,
                             "source": "measured, quick (regression guard; l0 = 1.1875 mm)"},
    "monotonic_peak_load": {"case": "monotonic", "quantity": "peak_load", "value": 6.451, "unit": "mm", "abs": 0.03,
                            "source": "measured, quick (regression guard; past the paper's turning point 6.3 mm)"},
}


# ---------------------------------------------------------------------- post-processing
def post_results(p: dict, history, results: dict) -> dict:
    """Add to the results of case ``main`` the numbers of :func:`phases` (forces in N, loads in mm,
    W_f in N mm), once the history has reached the turning point of the schedule."""
    if history is None or not len(history):
        return results
    if "monotonic" in results and "case" in history:
        m = history[history["case"] == "monotonic"]
        if len(m):
            results["monotonic"].update(monotonic_numbers(m))
    if "main" not in results:
        return results
    h = history[history["case"] == "main"] if "case" in history else history
    if not len(h) or not np.isclose(h["load"].to_numpy(dtype=float), effective_schedule(p)[1], atol=1e-9).any():
        return results
    results["main"].update(phases(h, p))
    return results


def monotonic_numbers(hist) -> dict:
    """Peak of the monotonic case and whether it was passed: ``first_peak_force`` (N) and
    ``first_peak_load`` (mm, the peak of ngtmc), ``final_force``, ``drop_after_peak`` (1 - final
    force / peak force) and ``peak_passed`` (the force fell by more than 5 % after the peak)."""
    h = hist.sort_values("step").reset_index(drop=True)
    j = peak_index(h["force"])
    if j is None:
        return {}
    fp, ff = float(h["force"].iloc[j]), float(h["force"].iloc[-1])
    drop = 1.0 - ff / fp if fp > 0 else float("nan")
    return {"first_peak_force": fp, "first_peak_load": float(h["load"].iloc[j]), "final_force": ff,
            "final_load": float(h["load"].iloc[-1]), "drop_after_peak": drop,
            "peak_passed": bool(j < len(h) - 1 and drop > 0.05),
            "wf_final": float(h["fracture_energy"].iloc[-1]), "max_alpha_final": float(h["max_alpha"].iloc[-1])}


def phases(hist, p: dict, settle: float = 0.25) -> dict:
    """Split a history (DataFrame of one case) into the schedule's phases and return the key numbers.

    first_peak_force / first_peak_load: largest force while loading to 6.3 mm (at the turning point
    if the peak was not reached); force_first_loading_at_gap: force at u = l_h on the first loading
    (interpolated); force_unloaded_at_gap: force at the end of unloading (u = l_h);
    reload_peak_force / reload_peak_load: largest force while reloading to 7 mm.

    Damage while unloading: the single-pass staggered scheme lags damage by one step, and the step
    rule (Eq. 20) makes the first unloading steps tiny when W_f grew fast just before the turning
    point, so the damage driven by the last loading states is still being applied in the first
    unloading steps, at loads within a few hundredths of a mm of the turning point.
    ``unload_wf_change`` and ``unload_max_alpha_change`` are therefore measured over the unloading
    steps after the first ``settle`` fraction of the unloading path (default 25 %, 0.075 mm);
    ``unload_wf_lag`` is the growth of W_f before that (from the turning point).
    """
    sched = effective_schedule(p)
    u1, u2, u3 = sched[1], sched[2], sched[3]
    h = hist.sort_values("step").reset_index(drop=True)
    load = h["load"].to_numpy()
    idx = np.arange(len(load))
    i1 = int(np.argmax(np.isclose(load, u1, atol=1e-9)))
    rest = np.where(np.isclose(load, u2, atol=1e-9) & (idx > i1))[0]
    i2 = int(rest[0]) if rest.size else len(load) - 1
    first = h.iloc[: i1 + 1]
    unload = h.iloc[i1: i2 + 1]
    reload = h.iloc[i2:]
    j = peak_index(first["force"]) or 0  # the peak of ngtmc (largest finite force), row 0 if none
    gap = effective_gap(p)
    u_settle = u1 - settle * abs(u1 - u2)
    settled = unload[unload["load"] <= u_settle + 1e-12]
    out = {
        "first_peak_force": float(first["force"].iloc[j]), "first_peak_load": float(first["load"].iloc[j]),
        "first_peak_before_turning_point": bool(j < len(first) - 1 and first["force"].iloc[-1] < first["force"].iloc[j]),
        "force_at_turning_point": float(first["force"].iloc[-1]),
        "force_first_loading_at_gap": float(np.interp(gap, first["load"], first["force"])),
        "force_unloaded_at_gap": float(unload["force"].iloc[-1]),
        "unload_steps": int(len(unload) - 1),
        "wf_at_turning_point": float(unload["fracture_energy"].iloc[0]),
        "max_alpha_at_turning_point": float(unload["max_alpha"].iloc[0]),
        "unload_wf_lag": float(settled["fracture_energy"].iloc[0] - unload["fracture_energy"].iloc[0]) if len(settled) else float("nan"),
        "unload_wf_change": float(settled["fracture_energy"].iloc[-1] - settled["fracture_energy"].iloc[0]) if len(settled) else float("nan"),
        "unload_max_alpha_change": float(settled["max_alpha"].iloc[-1] - settled["max_alpha"].iloc[0]) if len(settled) else float("nan"),
        "unload_settled_steps": int(len(settled)),
        "completed": bool(np.isclose(load[-1], u3)),
    }
    if len(reload) > 1:
        k = peak_index(reload["force"]) or 0
        out.update({"reload_peak_force": float(reload["force"].iloc[k]), "reload_peak_load": float(reload["load"].iloc[k]),
                    "final_force": float(reload["force"].iloc[-1]),
                    "wf_final": float(reload["fracture_energy"].iloc[-1])})
    return out


if __name__ == "__main__":  # python studies/l_panel.py [options of `ngtmc run`], e.g. --resolution medium
    import sys

    from ngtmc.cli import run_script
    sys.exit(run_script(NAME))
