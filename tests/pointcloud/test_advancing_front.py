"""Advancing front + sv.remesh on analytic surfaces: manifold, closed/open, quality, control."""

import numpy as np
import pc_surfaces as S
import pytest

import splineviz as sv
from splineviz.pointcloud.advancing_front import Cancelled
from splineviz.pointcloud.quality import edge_face_counts
from splineviz.pointcloud.remesh import RemeshError, RemeshReport


def _arrays(mesh):
    return np.asarray(mesh.points), np.asarray(mesh.faces).reshape(-1, 4)[:, 1:]


def _within_sag(dist, v, f, kappa):
    """Whether each vertex lies within the sag ``kappa L^2 / 8`` of its longest edge: the
    vertices are fitted to the surface in the least-squares sense (surface_fit), so they sit
    off it by about the sag of their edges, never by more than a fraction over it."""
    edges, _ = edge_face_counts(f)
    length = np.linalg.norm(v[edges[:, 0]] - v[edges[:, 1]], axis=1)
    longest = np.zeros(len(v))
    np.maximum.at(longest, edges[:, 0], length)
    np.maximum.at(longest, edges[:, 1], length)
    return bool(np.all(dist <= 1.5 * kappa * longest**2 / 8))


def _euler(v, f):
    edges, _ = edge_face_counts(f)
    return len(np.unique(f)) - len(edges) + len(f)


def _signed_volume(v, f):
    p = v[f]
    return np.einsum("ij,ij->i", p[:, 0], np.cross(p[:, 1], p[:, 2])).sum() / 6


@pytest.fixture(scope="module")
def sphere_mesh():
    pts = S.sphere(6000, seed=1)
    report = RemeshReport()
    mesh = sv.remesh(pts, edge_length=0.12, report=report)
    return pts, mesh, report


def test_sphere_is_closed_oriented_and_well_shaped(sphere_mesh):
    pts, mesh, report = sphere_mesh
    v, f = _arrays(mesh)
    q = sv.mesh_quality(mesh, reference=pts)
    assert q["boundary_edges"] == 0 and q["non_manifold_edges"] == 0
    assert _euler(v, f) == 2
    assert _signed_volume(v, f) == pytest.approx(4 / 3 * np.pi, rel=0.02)  # outward
    assert q["radius_ratio_mean"] > 0.93 and q["valence6_fraction"] > 0.7
    assert _within_sag(S.sphere_distance(v), v, f, 1.0)
    assert report.front["new_vertices"] > 0 and report.front["ears"] > 0


def test_edge_length_is_followed(sphere_mesh):
    _, mesh, _ = sphere_mesh
    v, f = _arrays(mesh)
    edges, _ = edge_face_counts(f)
    length = np.linalg.norm(v[edges[:, 0]] - v[edges[:, 1]], axis=1)
    assert np.median(length) == pytest.approx(0.12, rel=0.1)
    # an equilateral mesh of the sphere: F ~ area / (sqrt(3)/4 L^2)
    assert len(f) == pytest.approx(4 * np.pi / (np.sqrt(3) / 4 * 0.12**2), rel=0.15)


def test_torus_has_genus_one():
    pts = S.torus(8000, seed=2)
    mesh = sv.remesh(pts, edge_length=0.09)
    v, f = _arrays(mesh)
    q = sv.mesh_quality(mesh, reference=pts)
    assert q["boundary_edges"] == 0 and q["non_manifold_edges"] == 0
    assert _euler(v, f) == 0
    assert _within_sag(S.torus_distance(v), v, f, 1 / 0.4)  # the tube's curvature
    assert q["radius_ratio_mean"] > 0.9


def test_open_patch_keeps_its_border():
    pts = S.paraboloid(5000, seed=3)
    mesh = sv.remesh(pts, edge_length=0.07)
    v, f = _arrays(mesh)
    edges, counts = edge_face_counts(f)
    assert counts.max() == 2
    rim = np.unique(edges[counts == 1])
    r = np.hypot(v[rim, 0], v[rim, 1])
    # the border follows the rim of the scan (radius 1), within about one edge length
    assert len(rim) > 2 * np.pi / 0.07 * 0.6
    assert np.all(r > 1 - 0.1) and np.all(r < 1 + 0.04)
    assert _euler(v, f) == 1  # a disc
    assert _within_sag(S.paraboloid_distance(v), v, f, 1.0)  # 2 a at the apex


def test_curvature_adaptation():
    """With rho, edges are shorter where the surface bends more (tips of an ellipsoid)."""
    axes = np.array([1.0, 0.35, 0.35])
    pts = S.sphere(8000, seed=4) * axes
    mesh = sv.remesh(pts, rho=0.3, min_length=0.02, max_length=0.2)
    v, f = _arrays(mesh)
    edges, _ = edge_face_counts(f)
    mid = 0.5 * (v[edges[:, 0]] + v[edges[:, 1]])
    length = np.linalg.norm(v[edges[:, 0]] - v[edges[:, 1]], axis=1)
    tips = np.abs(mid[:, 0]) > 0.9  # curvature 1/0.1225 ~ 8 there, ~2.9 around the waist
    waist = np.abs(mid[:, 0]) < 0.3
    assert np.median(length[tips]) < 0.7 * np.median(length[waist])


def test_two_components_get_two_seeds():
    a = S.sphere(3000, seed=5)
    b = S.sphere(3000, seed=6) * 0.5 + np.array([3.0, 0, 0])
    report = RemeshReport()
    mesh = sv.remesh(np.vstack([a, b]), edge_length=0.15, report=report)
    v, f = _arrays(mesh)
    assert report.front["seeds"] == 2
    assert _euler(v, f) == 4
    assert sv.mesh_quality(mesh)["boundary_edges"] == 0


def test_progress_and_cancel():
    pts = S.sphere(3000, seed=7)
    seen = []
    sv.remesh(pts, edge_length=0.08, progress=lambda frac, msg: seen.append(frac))
    assert seen[0] == 0.0 and seen[-1] == 1.0
    assert np.all(np.diff(seen) >= 0) and len(seen) > 4
    with pytest.raises(Cancelled):
        sv.remesh(pts, edge_length=0.08, progress=lambda frac, msg: frac < 0.5)


def test_bad_input():
    with pytest.raises(RemeshError):
        sv.remesh(np.zeros((3, 3)))
    with pytest.raises(sv.SplinevizError):
        sv.remesh(S.sphere(500), edge_length=-1.0)
    with pytest.raises(sv.SplinevizError):
        sv.remesh(S.sphere(500), rho=4.0)
    with pytest.raises(sv.SplinevizError):
        sv.remesh(np.zeros((10, 2)))


def test_runaway_guard_stops_the_front(monkeypatch):
    """A front that produces far more vertices than the cloud has points is stopped and
    flagged instead of running on."""
    from splineviz.pointcloud import advancing_front

    monkeypatch.setattr(advancing_front, "VERTEX_BUDGET", 0)
    pts = S.sphere(3000, seed=8)
    report = RemeshReport()
    mesh = sv.remesh(pts, edge_length=0.03, report=report, optimize_mesh=False)
    assert report.front["truncated"] is True
    assert 1000 < mesh.n_points <= 1000 + 3


def _plane_front():
    from splineviz.pointcloud.advancing_front import AdvancingFront
    from splineviz.pointcloud.guidance import guidance_field
    from splineviz.pointcloud.projection import Projector

    rng = np.random.default_rng(9)
    pts = np.c_[rng.uniform(-2, 2, (1500, 2)), np.zeros(1500)]
    proj = Projector(pts)
    return AdvancingFront(proj, guidance_field(proj, edge_length=0.2))


def test_hole_triangulation_fills_a_non_convex_loop():
    front = _plane_front()
    # an L-shaped loop, counter-clockwise seen from +z (the cloud's normals face +z or -z)
    corners = [(0, 0), (1, 0), (1, 0.4), (0.4, 0.4), (0.4, 1), (0, 1)]
    up = np.array([0.0, 0.0, 1.0])
    loop = [front._add_vertex(np.array([x, y, 0.0]), up) for x, y in corners]
    tris = front._best_triangulation(loop)
    assert len(tris) == len(loop) - 2
    p = front.V[np.array(tris)]
    normals = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    assert np.all(normals[:, 2] > 0)  # all counter-clockwise: no triangle outside the L
    assert 0.5 * normals[:, 2].sum() == pytest.approx(1 - 0.6 * 0.6)
    # a diagonal that already is a mesh edge is never used
    front.edge_faces[(loop[0], loop[3])] = 2
    assert all({loop[0], loop[3]} - set(t) for t in front._best_triangulation(loop))


def test_laid_over_triangles_are_detected():
    front = _plane_front()
    up = np.array([0.0, 0.0, 1.0])
    ids = [front._add_vertex(np.array(x), up) for x in ([0, 0, 0], [0.2, 0, 0], [0.1, 0.17, 0])]
    front._add_triangle(*ids)
    centre = front.V[ids].mean(axis=0)
    assert front._covered(centre[None] + [0, 0, 0.01], centre, 0.2)
    assert not front._covered(centre[None] + [0, 0, 0.1], centre, 0.2)  # another sheet
    assert not front._covered(np.array([[0.3, 0.1, 0.0]]), centre, 0.2)  # beside it


def test_seeds_are_not_placed_on_the_mesh():
    front = _plane_front()
    pts = front.proj.points
    here = int(np.argmin(np.linalg.norm(pts, axis=1)))  # the input point nearest the origin
    up = np.array([0.0, 0.0, 1.0])
    corners = [pts[here] + d for d in ([-0.4, -0.3, 0], [0.4, -0.3, 0], [0, 0.4, 0])]
    front._add_triangle(*[front._add_vertex(np.asarray(x, dtype=float), up) for x in corners])
    assert not front._seed(here)
    far = int(np.argmax(np.linalg.norm(pts, axis=1)))  # a corner of the square, 2.8 away
    assert front._seed(far)


def test_given_up_edges_are_retried_and_holes_filled(monkeypatch):
    """Edges that fail are retried with shorter edges and what is left is filled: the sphere
    still comes out closed."""
    from splineviz.pointcloud import advancing_front

    monkeypatch.setattr(advancing_front, "GIVE_UP", 1)
    monkeypatch.setattr(advancing_front, "MIN_ANGLE_NEW", np.deg2rad(52.0))
    report = RemeshReport()
    mesh = sv.remesh(S.sphere(4000, seed=10), edge_length=0.15, report=report)
    v, f = _arrays(mesh)
    assert report.front["given_up"] > 0
    q = sv.mesh_quality(mesh)
    assert q["boundary_edges"] == 0 and q["non_manifold_edges"] == 0
    assert _euler(v, f) == 2


def test_pinched_loops_are_split_into_simple_ones():
    from splineviz.pointcloud.advancing_front import simple_loops

    # 1 -> 2 -> 3 -> 4 -> 2 -> 5 -> 6 -> 1 touches itself at 2
    parts = simple_loops([1, 2, 3, 4, 2, 5, 6])
    assert sorted(map(tuple, parts)) == [(1, 2, 5, 6), (2, 3, 4)]
    for part in parts:  # every directed edge of a part is an edge of the loop
        edges = set(zip(part, part[1:] + part[:1], strict=True))
        assert edges <= {(1, 2), (2, 3), (3, 4), (4, 2), (2, 5), (5, 6), (6, 1)}
    assert simple_loops([7, 8, 9]) == [[7, 8, 9]]


def test_loops_pinched_at_a_vertex_keep_every_edge():
    """Two front loops through vertex 0, whose two edges in both prefer the same edge out
    (the wedge choice at a thin part's rim): each edge is still on exactly one loop, the
    preferred continuation kept where it is free; an edge out of a vertex that nothing
    enters stays on no loop."""
    from splineviz.pointcloud.advancing_front import edge_loops

    edges = [(0, 1), (1, 2), (2, 0), (0, 3), (3, 4), (4, 0), (7, 8)]
    preferred = {(2, 0): (0, 1), (4, 0): (0, 1), (0, 1): (1, 2), (1, 2): (2, 0),
                 (0, 3): (3, 4), (3, 4): (4, 0), (7, 8): None}
    loops = edge_loops(edges, preferred)
    on = [set(zip(loop, loop[1:] + loop[:1], strict=True)) for loop in loops]
    assert sorted(len(e) for e in on) == [6] or sorted(len(e) for e in on) == [3, 3]
    assert set().union(*on) == set(edges) - {(7, 8)}
    assert sum(len(e) for e in on) == 6
    assert any((2, 0) in e and (0, 1) in e for e in on)  # the first keeps its choice
    # a loop whose edges agree is found as it was
    assert edge_loops([(5, 6), (6, 7), (7, 5)], {(5, 6): (6, 7), (6, 7): (7, 5),
                                                  (7, 5): (5, 6)}) == [[5, 6, 7]]


def test_heap_smallest_is_nsmallest():
    import heapq

    from splineviz.pointcloud.advancing_front import heap_smallest

    rng = np.random.default_rng(3)
    heap: list = []
    for counter in range(3000):
        # the front's entries: (delay, counter, a, b), many equal delays
        heapq.heappush(heap, (int(rng.integers(0, 4)), counter, 0, 0))
        if counter % 7 == 0:
            heapq.heappop(heap)
    for k in (0, 1, 5, 64, len(heap), len(heap) + 3):
        assert heap_smallest(heap, k) == heapq.nsmallest(k, heap)
    assert heap_smallest([], 4) == []


def test_the_triangle_test_accepts_a_fitting_triangle_and_refuses_each_fault():
    """The compiled validity test of a front step's triangle, one fault at a time, on a
    triangle built on the plane (front edges a -> b, b -> c, c -> a facing +z: the
    unmeshed side of a -> b is its right, seen from +z)."""
    front = _plane_front()
    up = np.array([0.0, 0.0, 1.0])
    a, b, c = (front._add_vertex(np.array(x), up)
               for x in ([0.0, 0.0, 0.0], [0.2, 0.0, 0.0], [0.1, 0.17, 0.0]))
    front._add_triangle(a, b, c)
    assert (b, a) in front.front  # the new triangle's edges face the unmeshed plane around it
    n = (0.0, 0.0, 1.0)
    ok = front._triangle_ok
    below = (0.1, -0.17, 0.0)  # the equilateral apex on the unmeshed side of b -> a
    assert ok(b, a, -1, below, n, np.deg2rad(30), False)
    assert not ok(b, a, -1, below, (0.0, 0.0, -1.0), np.deg2rad(30), False)  # faces away
    assert not ok(b, a, -1, (0.1, -0.02, 0.0), n, np.deg2rad(30), False)  # a sliver
    # the apex at a front vertex whose new edges would leave it into meshed space (c lies on
    # the other side of a -> b, the triangle would fold over abc)
    assert not ok(b, a, c, front.P[c], n, np.deg2rad(10), True)
    # the same triangle on a front edge inside the cloud fits, past the cloud's end (0.2
    # beyond its last points, two spacings) it spans a hole of the scan
    for y, inside in ((1.0, True), (front.proj.points[:, 1].min() - 0.2, False)):
        d, e, f = (front._add_vertex(np.array(x), up)
                   for x in ([0.0, y, 0.0], [0.2, y, 0.0], [0.1, y + 0.17, 0.0]))
        front._add_triangle(d, e, f)
        assert ok(e, d, -1, (0.1, y - 0.17, 0.0), n, np.deg2rad(30), False) is inside
