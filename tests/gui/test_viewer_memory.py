"""One copy of the geometry between the library and the display, and no frame drawn for nothing
(issue 20 item 11: the viewer's memory and time to first picture on large meshes)."""

from __future__ import annotations

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy

from curv.normals import cached_max_normals

from app.model import SurfaceSource


def test_display_reads_the_mesh_arrays_and_the_estimate_its_normals(qtbot, window, ui):
    ui.open_surface("torus", n_vertices=2000)
    mesh = window.doc.mesh
    poly = window.grid.viewports[0].poly
    cells = poly.GetPolys()
    # the points and the faces VTK draws are the mesh's own memory, not copies
    assert np.shares_memory(np.asarray(poly.points), mesh.vertices)
    assert np.shares_memory(vtk_to_numpy(cells.GetConnectivityArray()), mesh.face_indices)
    assert np.shares_memory(vtk_to_numpy(cells.GetOffsetsArray()), mesh.face_offsets)
    np.testing.assert_array_equal(vtk_to_numpy(cells.GetConnectivityArray()), mesh.face_indices)
    # the shading normals and the estimate's normals are one computation: the mesh's cached normals
    normals = cached_max_normals(mesh)
    np.testing.assert_array_equal(vtk_to_numpy(poly.GetPointData().GetNormals()), normals.astype(np.float32))
    result = window.doc.result(0)
    assert result.normals is normals


def test_estimates_start_before_the_views_draw_a_new_mesh(qtbot, window, ui):
    ui.open_surface("sphere", n_vertices=642)
    running_when_drawn = []
    # connected after the window's own handler: it runs once the views have drawn the mesh
    window.doc.mesh_changed.connect(lambda change: running_when_drawn.append(window.controller.running_keys()))
    window.open_surface(SurfaceSource(name="torus", n_vertices=2000))
    ui.wait_ready()
    assert running_when_drawn == [[window.doc.panes[0].key]]


def test_framing_the_camera_draws_no_frame_unless_asked(qtbot, window, ui):
    ui.open_surface("sphere", n_vertices=642)
    frames = []
    for vp in window.grid.viewports:
        vp.plotter.render = lambda *a, _render=vp.plotter.render, **k: (frames.append(1), _render(*a, **k))
    window.grid.reset_camera(render=False)
    assert frames == []
    window.grid.reset_camera(render=True)
    assert frames
