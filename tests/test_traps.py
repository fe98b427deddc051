"""The NGSolve traps of NGSOLVE_NOTES.md that touch this code, each pinned: the trap itself is shown
to give a wrong number silently, and ngtmc is shown to avoid it."""
import dataclasses
import math

import numpy as np
import ngsolve as ngs
import pytest

import ngtmc
from scenes import bar_mesh, tension_bar, two_blocks


def test_history_terms_are_integrated_at_the_history_points():
    """An IntegrationRuleSpace of order p uses a rule of order 2p; a plain dx on the P1 phase field
    would use order 2 and read the history at the wrong points (an IRS field is 0 elsewhere)."""
    scene = dataclasses.replace(two_blocks(), fracture_regions="lower", variable_order=False)  # order 2: rules differ
    s = ngtmc.Solver(scene)
    assert s.order == 2
    # history = a smooth function sampled at the rule points: the load vector integrates it exactly
    f = ngs.sin(3 * ngs.x) * ngs.exp(ngs.y) + 2
    s.H.Interpolate(f)
    s.f_alpha.Assemble()
    exact = 2 * ngs.Integrate(f, s.mesh, definedon=s.mesh.Materials("lower"), order=12)
    assert sum(s.f_alpha.vec.FV().NumPy()) == pytest.approx(exact, rel=1e-9)
    # the trap: the same form with the default rule silently reads other values
    beta = s.fes_a.TestFunction()
    wrong = ngs.LinearForm(2 * s.H * beta * ngs.dx(definedon=s.mesh.Materials("lower")))
    s.H.vec.FV().NumPy()[:] = np.random.default_rng(0).uniform(0, 1, s.irs.ndof)
    s.f_alpha.Assemble()
    wrong.Assemble()
    ours, theirs = sum(s.f_alpha.vec.FV().NumPy()), sum(wrong.vec.FV().NumPy())
    assert abs(ours - theirs) > 1e-3 * abs(ours)


def test_history_update_is_a_pointwise_maximum_at_the_rule_points():
    s = ngtmc.Solver(tension_bar())
    rng = np.random.default_rng(0)
    s.H_committed = rng.uniform(0, 1e-3, s.irs.ndof)
    s.u.Set(ngs.CF((0.01 * ngs.x, -0.003 * ngs.y)))
    plus = s.psi_plus_values()
    s.update_history()
    np.testing.assert_array_equal(s.H_committed, np.maximum(plus, s.H_committed))


def test_setting_a_vector_on_a_boundary_overwrites_the_other_component():
    """The trap: gfu.Set(CF((v, 0)), definedon=...) writes 0 into the y dofs there."""
    mesh = bar_mesh()
    gfu = ngs.GridFunction(ngs.VectorH1(mesh, order=1))
    gfu.components[1].Set(0.5)
    gfu.Set(ngs.CF((0.1, 0)), definedon=mesh.Boundaries("right"))
    assert gfu.components[1](mesh(1.0, 0.1)) == pytest.approx(0.0)


def test_loaded_boundary_keeps_its_free_component():
    """ngtmc sets one component only: the loaded edge of a bar in tension contracts laterally."""
    res = ngtmc.simulate(tension_bar(fracture=False), 0.01, ngtmc.AdaptiveStepControl(du_max=0.005))
    uy = res.solver.u.components[1](res.solver.mesh(1.0, 0.2))
    assert uy < -1e-4  # plane strain: about -nu/(1-nu) * 0.01 * 0.2


def test_writing_boundary_values_into_the_solution_inverts_elements_but_lifting_does_not():
    mesh = bar_mesh(length=1.0, height=0.4, maxh=0.05)
    scene = ngtmc.Scene(mesh, {"bar": ngtmc.Material(1000.0, 0.3)}, supports=[ngtmc.Support("bottom", x=True, y=True)],
                        load=ngtmc.DisplacementLoad("top", "-y", hold_tangential=True))
    s = ngtmc.Solver(scene)
    # the trap: write -0.08 on the top edge into u directly (top elements are ~0.05 high)
    s.u.components[1].Set(-0.08, definedon=mesh.Boundaries("top"))
    assert np.isnan(s.a_u.Energy(s.u.vec))
    # ngtmc: the Newton increment carries the boundary value; one step of 20 % compression converges
    s.u.vec[:] = 0.0
    res = s.solve_displacement(0.08)
    assert res.converged
    assert s.min_J() > 0.5
    assert np.isfinite(s.a_u.Energy(s.u.vec))


def test_energy_is_nan_when_an_element_inverts_and_the_guard_sees_it():
    s = ngtmc.Solver(tension_bar(fracture=False))
    s.u.Set(ngs.CF((-1.5 * ngs.x, 0)))  # J = -0.5
    assert np.isnan(s.a_u.Energy(s.u.vec))
    assert np.isnan(s._energy(s.u.vec))
    assert s.min_J() < 0


def test_symmetric_solver_agrees_with_general_lu_on_a_contact_step():
    """sparsecholesky silently accepts a non-symmetric matrix; ngtmc's tangents are symmetric
    (pure energies, no weak-form-only terms), so it must agree with umfpack."""
    forces = []
    for solver in ("sparsecholesky", "umfpack"):
        sim = ngtmc.Simulation(two_blocks(), 0.045, ngtmc.AdaptiveStepControl(du_max=0.015),
                               newton=ngtmc.NewtonOptions(linear_solver=solver))
        forces.append(sim.run().history["force"].to_numpy())
    np.testing.assert_allclose(forces[0], forces[1], rtol=1e-7, atol=1e-12)


def test_tangent_is_symmetric():
    s = ngtmc.Solver(two_blocks())
    s.u.Set(ngs.CF((0.01 * ngs.x * ngs.y, -0.02 * ngs.y ** 2)))
    a = ngs.BilinearForm(s.fes_u, symmetric=False)
    for _, density, regions in s.energy_terms(s.fes_u.TrialFunction()):
        a += ngs.Variation(density * ngs.dx(definedon=s.mesh.Materials(regions)))
    a.AssembleLinearization(s.u.vec)
    import scipy.sparse as sp
    rows, cols, vals = a.mat.COO()
    K = sp.csr_matrix((np.asarray(vals), (np.asarray(rows), np.asarray(cols))))
    assert abs(K - K.T).max() < 1e-10 * abs(K).max()


def _one_triangle_scene(order):
    """The reference triangle (0,0), (1,0), (0,1) as a one-element mesh (mm)."""
    from netgen.meshing import Element1D, Element2D, FaceDescriptor, Mesh, MeshPoint
    from netgen.csg import Pnt
    m = Mesh(dim=2)
    pts = [m.Add(MeshPoint(Pnt(x, y, 0))) for x, y in ((0, 0), (1, 0), (0, 1))]
    m.Add(FaceDescriptor(surfnr=1, domin=1, bc=1))
    m.Add(Element2D(1, pts))
    for k, (a, b) in enumerate(((0, 1), (1, 2), (2, 0)), start=1):
        m.Add(Element1D([pts[a], pts[b]], index=k))
    for k, name in enumerate(("bottom", "hyp", "left"), start=1):
        m.SetBCName(k - 1, name)
    m.SetMaterial(1, "solid")
    mesh = ngs.Mesh(m)
    return ngtmc.Scene(mesh=mesh, materials={"solid": ngtmc.Material(E=100.0, nu=0.3, Gc=1.0, l0=1.0)},
                       supports=[ngtmc.Support("left", x=True)], load=ngtmc.DisplacementLoad("bottom", direction="y"),
                       order=order)


def test_order_two_elastic_energy_sees_a_fold_between_the_default_points():
    """The trap: a Variation integrates an order-2 elastic energy with NGSolve's default rule of
    order 2p - 2 = 2 (the three edge midpoints of a triangle). u_y = -0.8 y^2 folds the element for
    y > 0.625 (J = 1 - 1.6 y < 0) while J = 0.2 > 0 at all three midpoints: the default-rule energy
    is finite, so Newton can walk into such folds (it stalled in the squeezed void of the three-point
    bending run). ngtmc integrates the elastic terms at the history points (order 4, six points, one
    at y = 0.817): the folded state has no finite energy."""
    s = ngtmc.Solver(_one_triangle_scene(order=2))
    s.u.Set(ngs.CF((0, -0.8 * ngs.y ** 2)))
    uT = s.fes_u.TrialFunction()
    default = ngs.BilinearForm(s.fes_u)
    for name, dens, reg in s.energy_terms(uT):
        default += ngs.Variation(dens * ngs.dx(definedon=s.mesh.Materials(reg)))
    assert math.isfinite(default.Energy(s.u.vec))  # the trap: a folded element with finite energy
    assert not math.isfinite(s.a_u.Energy(s.u.vec))
    # an unfolded quadratic field: the energy is the order-4 integral of the density
    s.u.Set(ngs.CF((0.05 * ngs.x * ngs.y, -0.3 * ngs.y ** 2)))
    dens = sum(d for _, d, _ in s.energy_terms(s.u))
    assert s.a_u.Energy(s.u.vec) == pytest.approx(ngs.Integrate(dens, s.mesh, order=4), rel=1e-12)
    assert default.Energy(s.u.vec) != pytest.approx(s.a_u.Energy(s.u.vec), rel=1e-6)


def test_linear_elements_keep_the_one_point_rule():
    """P1 displacements have a constant F per element: the one-point default rule is exact."""
    s = ngtmc.Solver(_one_triangle_scene(order=1))
    s.u.Set(ngs.CF((0.01 * ngs.x, -0.02 * ngs.y + 0.005 * ngs.x)))
    dens = sum(d for _, d, _ in s.energy_terms(s.u))
    assert s.a_u.Energy(s.u.vec) == pytest.approx(ngs.Integrate(dens, s.mesh, order=6), rel=1e-12)


def test_sparse_cholesky_reproduces_only_to_round_off():
    """Two factorizations of the same matrix by sparsecholesky, in one process, may solve to
    different last bits (measured 1e-16 relative, 2026-11-24); umfpack solves bitwise alike. So two
    identical runs agree to round-off, not bitwise, and a run's discrete decisions (a cut-back
    that only just happens) can differ: compare runs with tolerances (docs/performance.md,
    "Reproducibility")."""
    from netgen.occ import unit_square
    m = ngs.Mesh(unit_square.GenerateMesh(maxh=0.05))
    V = ngs.VectorH1(m, order=2, dirichlet=".*")
    u, v = V.TnT()
    a = ngs.BilinearForm(V, symmetric=True)
    a += (ngs.InnerProduct(ngs.Grad(u), ngs.Grad(v)) + u * v) * ngs.dx
    a.Assemble()
    f = ngs.LinearForm(V)
    f += ngs.CF((ngs.x, ngs.x * ngs.y)) * v * ngs.dx
    f.Assemble()

    def solve(inverse):
        x = a.mat.CreateColVector()
        x.data = a.mat.Inverse(V.FreeDofs(), inverse=inverse) * f.vec
        return x.FV().NumPy().copy()
    ch = [solve("sparsecholesky") for _ in range(3)]
    lu = [solve("umfpack") for _ in range(2)]
    assert np.array_equal(lu[0], lu[1])
    scale = np.abs(lu[0]).max()
    for x in ch:
        assert np.abs(x - lu[0]).max() <= 1e-13 * scale


def test_gmres_function_tolerance_is_absolute():
    """``ngsolve.krylovspace.GMRes(tol=)`` is an absolute tolerance on the preconditioned residual
    (it is passed on as ``atol``; ``reltol`` is the relative one). A small right-hand side is then
    'solved' by the zero vector, silently: here a Poisson load of 1e-9 with tol = 1e-6 returns
    x = 0. A Newton correction of a nearly converged step is such a small right-hand side, so the
    coupled solver uses ``GMResSolver(tol=relative)`` (:class:`ngtmc.coupled.monolithic.CoupledNewton`,
    ``gmres_rtol``); measured 2026-11-25, ngsolve 6.2.2608."""
    from netgen.occ import unit_square
    from ngsolve.krylovspace import GMRes, GMResSolver
    m = ngs.Mesh(unit_square.GenerateMesh(maxh=0.1))
    V = ngs.H1(m, order=1, dirichlet="left")
    u, v = V.TnT()
    a = ngs.BilinearForm(ngs.grad(u) * ngs.grad(v) * ngs.dx).Assemble()
    f = ngs.LinearForm(1e-9 * v * ngs.dx).Assemble()
    exact = a.mat.CreateColVector()
    exact.data = a.mat.Inverse(V.FreeDofs(), inverse="umfpack") * f.vec
    ex = exact.FV().NumPy()
    pre = a.mat.CreateSmoother(V.FreeDofs())
    absolute = GMRes(a.mat, f.vec, pre=pre, tol=1e-6, printrates=False)
    assert np.linalg.norm(ex) > 1e-9 and np.linalg.norm(absolute.FV().NumPy()) == 0.0
    relative = GMResSolver(mat=a.mat, pre=pre, tol=1e-6, atol=1e-300, maxiter=200, printrates=False).Solve(rhs=f.vec)
    assert np.linalg.norm(relative.FV().NumPy() - ex) <= 1e-5 * np.linalg.norm(ex)


def test_an_energy_on_facets_integrates_to_zero_but_the_same_bilinear_form_does_not():
    """A ``Variation`` (energy) over ``dx(skeleton=True)`` or ``dx(element_boundary=True)`` is
    accepted and silently contributes nothing: energy and residual zero, the tangent zero to
    round-off (NGSolve 6.2.2608, measured; not in NGSOLVE_NOTES.md). The quadratic
    energy 1/2 sum over interior edges |e| |[[grad u]]|^2 (the jump term a regulariser of linear
    void elements would need: the paper L-panel stalls on a squeezed P1 void layer,
    benchmarks/results/l_panel-paper-stall-diagnosis-20261207T153000Z.md) is assembled correctly as
    a bilinear form on the skeleton: checked against the sum over edges of the element gradients."""
    from netgen.geom2d import unit_square
    mesh = ngs.Mesh(unit_square.GenerateMesh(maxh=0.3))
    fes = ngs.VectorH1(mesh, order=1, dgjumps=True)
    g = ngs.GridFunction(fes)
    g.Set(ngs.CF((ngs.x * ngs.y, ngs.x ** 2)))
    # by hand: the P1 gradient of each triangle, the jump across each interior edge
    pts = np.array([v.point for v in mesh.vertices])
    ux = np.stack([g.vec.FV().NumPy()[list(fes.GetDofNrs(ngs.NodeId(ngs.VERTEX, i)))] for i in range(mesh.nv)])
    grads, edges = [], {}
    for k, el in enumerate(mesh.Elements(ngs.VOL)):
        v = [x.nr for x in el.vertices]
        A = np.array([pts[v[1]] - pts[v[0]], pts[v[2]] - pts[v[0]]])
        dU = np.array([ux[v[1]] - ux[v[0]], ux[v[2]] - ux[v[0]]])
        grads.append(np.linalg.solve(A, dU).T)      # grad u, rows: components
        for a, b in ((v[0], v[1]), (v[1], v[2]), (v[2], v[0])):
            edges.setdefault(frozenset((a, b)), []).append(k)
    exact = sum(0.5 * np.linalg.norm(pts[a] - pts[b]) * np.sum((grads[ks[0]] - grads[ks[1]]) ** 2)
                for e, ks in edges.items() if len(ks) == 2 for a, b in [tuple(e)])
    assert exact > 1e-3
    u, v = fes.TnT()
    b = ngs.BilinearForm(fes)
    b += ngs.InnerProduct(ngs.Grad(u) - ngs.Grad(u).Other(), ngs.Grad(v) - ngs.Grad(v).Other()) * ngs.dx(skeleton=True)
    b.Assemble()
    w = g.vec.CreateVector()
    w.data = b.mat * g.vec
    assert 0.5 * ngs.InnerProduct(g.vec, w) == pytest.approx(exact, rel=1e-10)
    # the trap: the same energy as a Variation is zero, and so are its residual and tangent
    u = fes.TrialFunction()
    jump = ngs.Grad(u) - ngs.Grad(u).Other()
    for measure in (ngs.dx(skeleton=True), ngs.dx(element_boundary=True)):
        a = ngs.BilinearForm(fes)
        a += ngs.Variation(0.5 * ngs.InnerProduct(jump, jump) * measure)
        assert a.Energy(g.vec) == 0.0
        a.Apply(g.vec, w)
        assert w.Norm() == 0.0
        a.AssembleLinearization(g.vec)   # zero to round-off, against entries of order one in b's matrix
        assert np.abs(np.asarray(a.mat.COO()[2])).max() < 1e-12 * np.abs(np.asarray(b.mat.COO()[2])).max()
