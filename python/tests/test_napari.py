"""The napari plugin (slabscope._napari, manifest napari.yaml): the widget analyses an image
layer in a worker thread, adds labels lying on the image, the ranking as a table, the exploded
view as an RGB layer, and stops when cancelled. Headless (QT_QPA_PLATFORM=offscreen, no X
needed): the widget is a Qt widget, driven with pytest-qt, over napari's viewer model (the
viewer without its OpenGL canvas, which an offscreen Qt cannot draw: the layers, their events and
`add_labels`/`add_image` the widget uses are the model's). Without napari and pytest-qt these tests are skipped, except under `CI=true`, where
`.ci/run` installs them."""

from __future__ import annotations

import os

import numpy as np
import pytest
from conftest import run_mypy

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

try:
    import napari
    import pytestqt  # noqa: F401
except ImportError as missing:
    if os.environ.get("CI") == "true":
        raise
    pytest.skip(
        f"the napari plugin's tests need napari, a Qt binding and pytest-qt "
        f"(pip install 'slabscope[napari]' 'napari[pyqt5]' pytest-qt): {missing}",
        allow_module_level=True,
    )

import slabscope
from slabscope._napari import (
    SlabsWidget,
    _shown,
    axis_to_napari,
    displayed_indices,
    to_napari,
    to_slabscope,
    volume_of_layer,
)

# Worker threads finish within this (ms).
WAIT = 120_000


def layered_zyx(shape: tuple[int, int, int], seed: int = 1) -> np.ndarray:
    """A napari-ordered (z, y, x) float32 volume: four layers along z on a dark border, with a
    little noise."""
    rng = np.random.default_rng(seed)
    nz, ny, nx = shape
    data = np.zeros(shape, np.float32)
    z = np.arange(nz)[:, None, None]
    data[:] = 40.0 + 30.0 * (z * 4 // nz)
    data[:, :2, :] = 0.0
    data += rng.normal(0.0, 2.0, shape).astype(np.float32)
    return data


def test_axes_map_both_ways():
    zyx = np.arange(24).reshape(2, 3, 4)
    xyz = to_slabscope(zyx)
    assert xyz.shape == (4, 3, 2) and xyz[3, 1, 0] == zyx[0, 1, 3]
    assert np.array_equal(to_napari(xyz), zyx) and to_napari(xyz).flags.c_contiguous
    assert axis_to_napari((1.0, 0.0, 0.0)) == (0.0, 0.0, 1.0)


def viewer_model() -> napari.components.ViewerModel:
    """napari's viewer without its window and canvas."""
    return napari.components.ViewerModel()


def test_the_widget_lays_labels_on_the_image_and_ranks_the_views(qtbot):
    viewer = viewer_model()
    data = layered_zyx((32, 20, 24))
    scale, translate = (2.0, 0.5, 0.75), (10.0, -5.0, 3.0)
    image = viewer.add_image(data, name="img", scale=scale, translate=translate)
    viewer.add_image(np.zeros((8, 8), np.float32), name="flat")
    widget = SlabsWidget(viewer)
    qtbot.addWidget(widget)
    assert [widget.layer_box.itemText(i) for i in range(widget.layer_box.count())] == ["img"]
    widget.run()
    qtbot.waitUntil(lambda: widget.worker is None, timeout=WAIT)
    assert widget.status.text().endswith("(z, y, x)."), widget.status.text()

    # slabscope's own analysis of the same voxels, taken in its order with the layer's spacing.
    volume = slabscope.Volume.from_array(np.transpose(data, (2, 1, 0)), spacing=(0.75, 0.5, 2.0))
    analysis = slabscope.analyze(volume)
    assert widget.analysis is not None and widget.analysis.to_dict() == analysis.to_dict()
    labels = viewer.layers["img slabs"]
    assert isinstance(labels, napari.layers.Labels)
    assert np.array_equal(labels.data, np.transpose(analysis.labels(), (2, 1, 0)))
    np.testing.assert_array_equal(labels.scale, image.scale)
    np.testing.assert_array_equal(labels.translate, image.translate)
    np.testing.assert_array_equal(labels.affine.affine_matrix, image.affine.affine_matrix)
    for point in ([0, 0, 0], [31, 19, 23], [5, 7, 11]):
        np.testing.assert_allclose(labels.data_to_world(point), image.data_to_world(point))
    # Layers along napari's z: the slabs are cut across it, each z plane of the layers one slab,
    # labels counting from 1.
    assert abs(axis_to_napari(analysis.best_axis)[0]) > 0.99
    for plane in labels.data:
        assert len(set(np.unique(plane[2:]))) == 1
    assert set(np.unique(labels.data[:, 2:])) == set(range(1, len(analysis.slabs) + 1))

    # The table: the views, best first, their axes in napari's order.
    views = analysis.views
    assert widget.table.rowCount() == len(views) > 1
    for row, view in enumerate(views):
        assert widget.table.item(row, 0).text() == _shown(axis_to_napari(view["axis"]))
        assert widget.table.item(row, 1).text() == f"{view['entropy_rate']:.4f}"
        # The defaults rank by the mean over lattice phases: the third column, in the list's order.
        assert widget.table.item(row, 2).text() == f"{view['phases']['mean']:.4f}"
    means = [float(widget.table.item(row, 2).text()) for row in range(len(views))]
    assert means == sorted(means)

    # The exploded view, as an RGB image layer.
    assert widget.view_button.isEnabled()
    widget.add_exploded_view()
    qtbot.waitUntil(lambda: widget.worker is None, timeout=WAIT)
    view = viewer.layers["img exploded view"]
    assert view.rgb
    assert np.array_equal(view.data, np.asarray(slabscope.render(volume, analysis)))


def test_cancel_stops_a_run(qtbot):
    viewer = viewer_model()
    viewer.add_image(layered_zyx((96, 96, 96), seed=2), name="big")
    widget = SlabsWidget(viewer)
    qtbot.addWidget(widget)
    widget.run()
    assert widget.cancel_button.isEnabled() and not widget.run_button.isEnabled()
    widget.cancel()
    qtbot.waitUntil(lambda: widget.worker is None, timeout=WAIT)
    assert widget.status.text() == "Cancelled."
    # Stopped inside the analysis, at a progress report, not after it.
    assert widget.cancelled_in is not None, "the analysis ran to its end"
    assert widget.analysis is None and "big slabs" not in viewer.layers
    assert widget.run_button.isEnabled() and not widget.view_button.isEnabled()


def test_layers_slabscope_cannot_analyse_are_named():
    class Layer:
        name, rgb, ndim, multiscale = "photo", True, 3, False
        data = np.zeros((2, 4, 5, 6), np.float32)
        scale = (1.0, 1.0, 1.0, 1.0)

    with pytest.raises(ValueError, match="'photo' is RGB: slabscope analyses single-channel images"):
        volume_of_layer(Layer())  # type: ignore[arg-type]
    Layer.rgb, Layer.ndim = False, 2
    with pytest.raises(ValueError, match="'photo' is 2D"):
        volume_of_layer(Layer())  # type: ignore[arg-type]
    Layer.ndim = 4
    for at in ((), (2,), (0, 0)):
        with pytest.raises(ValueError, match=r"'photo' has data of shape \(2, 4, 5, 6\): expected 1 indices"):
            volume_of_layer(Layer(), at)  # type: ignore[arg-type]
    assert volume_of_layer(Layer(), (1,)).shape == (6, 5, 4)  # type: ignore[arg-type]


def frames_tzyx(nt: int, shape: tuple[int, int, int]) -> np.ndarray:
    """``nt`` (z, y, x) volumes, each its own: layers along z, then along y, then along x..."""
    frames = []
    for t in range(nt):
        frame = layered_zyx(shape, seed=10 + t)
        if t % 3 == 1:
            frame = np.ascontiguousarray(np.transpose(layered_zyx((shape[1], shape[0], shape[2]), 10 + t), (1, 0, 2)))
        elif t % 3 == 2:
            frame = np.ascontiguousarray(np.transpose(layered_zyx((shape[2], shape[1], shape[0]), 10 + t), (2, 1, 0)))
        frames.append(frame)
    return np.stack(frames)


def test_a_4d_layer_is_analysed_at_the_volume_displayed_and_labelled_there(qtbot):
    viewer = viewer_model()
    data = frames_tzyx(3, (24, 16, 20))
    # A time step of 3 and a world affine that scales time and turns (y, x): the labels must be
    # moved through both to lie on the time point.
    turn = np.eye(5)
    turn[0, 0] = 2.0
    turn[2:4, 2:4] = [[0.8, -0.6], [0.6, 0.8]]
    image = viewer.add_image(
        data, name="cine", scale=(3.0, 2.0, 0.5, 0.75), translate=(100.0, 10.0, -5.0, 3.0), affine=turn
    )
    viewer.dims.set_current_step(0, 2)
    assert displayed_indices(image, viewer) == (2,)
    widget = SlabsWidget(viewer)
    qtbot.addWidget(widget)
    assert [widget.layer_box.itemText(i) for i in range(widget.layer_box.count())] == ["cine"]
    widget.run()
    assert "cine, the 3D volume displayed: data[2, :, :, :] of its 4D data" in widget.status.text()
    qtbot.waitUntil(lambda: widget.worker is None, timeout=WAIT)
    assert widget.status.text().endswith("(z, y, x) of cine, the 3D volume displayed: data[2, :, :, :] of its 4D data.")

    # The analysis of time point 2, not of another.
    def analysed(t: int) -> slabscope.Analysis:
        volume = slabscope.Volume.from_array(to_slabscope(data[t]), spacing=(0.75, 0.5, 2.0))
        return slabscope.analyze(volume)

    analysis = analysed(2)
    assert widget.analysis is not None and widget.analysis.to_dict() == analysis.to_dict()
    assert analysis.to_dict() != analysed(0).to_dict() and analysis.to_dict() != analysed(1).to_dict()

    # Labels of the layer's four axes, one time point long, lying on time point 2.
    labels = viewer.layers["cine slabs"]
    assert labels.data.shape == (1, 24, 16, 20)
    assert np.array_equal(labels.data[0], to_napari(analysis.labels()))
    for point in ([0, 0, 0], [23, 15, 19], [5, 7, 11]):
        np.testing.assert_allclose(labels.data_to_world([0, *point]), image.data_to_world([2, *point]), atol=1e-9)
    # Where the sliders stand, the labels' one time point; elsewhere none of theirs.
    assert np.rint(labels.world_to_data(viewer.dims.point)[0]) == 0
    viewer.dims.set_current_step(0, 0)
    assert np.rint(labels.world_to_data(viewer.dims.point)[0]) == -2


def test_a_channel_axis_and_time_are_indexed_where_the_sliders_stand(qtbot):
    viewer = viewer_model()
    data = frames_tzyx(4, (16, 12, 14)).reshape(2, 2, 16, 12, 14)
    image = viewer.add_image(data, name="tc")
    viewer.dims.set_current_step(0, 1)
    viewer.dims.set_current_step(1, 0)
    assert displayed_indices(image, viewer) == (1, 0)
    widget = SlabsWidget(viewer)
    qtbot.addWidget(widget)
    widget.run()
    qtbot.waitUntil(lambda: widget.worker is None, timeout=WAIT)
    volume = slabscope.Volume.from_array(to_slabscope(data[1, 0]), spacing=(1.0, 1.0, 1.0))
    assert widget.analysis is not None and widget.analysis.to_dict() == slabscope.analyze(volume).to_dict()
    labels = viewer.layers["tc slabs"]
    assert labels.data.shape == (1, 1, 16, 12, 14)
    np.testing.assert_allclose(labels.data_to_world([0, 0, 3, 4, 5]), image.data_to_world([1, 0, 3, 4, 5]))


def test_an_rgb_layer_is_refused_saying_why(qtbot):
    viewer = viewer_model()
    viewer.add_image(np.zeros((6, 8, 10, 3), np.uint8), name="photo", rgb=True)
    widget = SlabsWidget(viewer)
    qtbot.addWidget(widget)
    widget.run()
    assert widget.worker is None
    assert widget.status.text() == (
        "layer 'photo' is RGB: slabscope analyses single-channel images "
        "(split its colours into layers of their own first)"
    )
    assert [layer.name for layer in viewer.layers] == ["photo"]


def test_the_tables_columns_show_their_headers_whole_in_a_narrow_dock(qtbot):
    viewer = viewer_model()
    widget = SlabsWidget(viewer)
    qtbot.addWidget(widget)
    widget.resize(120, 500)
    widget.show()
    qtbot.waitExposed(widget)

    def whole() -> None:
        header = widget.table.horizontalHeader()
        metrics = header.fontMetrics()
        for column in range(widget.table.columnCount()):
            text = widget.table.horizontalHeaderItem(column).text()
            size = header.sectionSize(column)
            assert size >= metrics.horizontalAdvance(text), (text, size)
            # Within the table's view: not cut by the dock's edge.
            assert header.sectionViewportPosition(column) + size <= header.viewport().width(), text

    whole()
    volume = slabscope.Volume.from_array(to_slabscope(layered_zyx((16, 12, 14))))
    widget.fill_table(slabscope.analyze(volume))
    qtbot.wait(10)
    whole()
    header = widget.table.horizontalHeader()
    metrics = header.fontMetrics()
    for row in range(widget.table.rowCount()):
        for column in range(2):
            text = widget.table.item(row, column).text()
            assert header.sectionSize(column) >= metrics.horizontalAdvance(text), text


def test_the_manifest_names_the_widget():
    import npe2
    from npe2.manifest.utils import import_python_name

    manifest = npe2.PluginManifest.from_distribution("slabscope")
    (widget,) = manifest.contributions.widgets
    (command,) = manifest.contributions.commands
    assert widget.command == command.id
    assert import_python_name(command.python_name) is SlabsWidget


def test_mypy_strict_accepts_the_plugin(tmp_path):
    pytest.importorskip("mypy", reason="the typing check needs mypy: pip install mypy")
    run_mypy(tmp_path, "mypy", "--strict", "-m", "slabscope._napari")
