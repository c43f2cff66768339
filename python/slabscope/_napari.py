"""slabscope in napari: a dock widget (the npe2 manifest ``napari.yaml`` of this package, installed
with ``pip install "slabscope[napari]"``) that analyses the image layer picked in a worker thread,
with progress and cancel; adds the slabs as a Labels layer lying on the image (label = slab index
+ 1, 0 for background), the views ranked as a table, and, on demand, the exploded view as an RGB
image layer.

napari indexes a 3D layer's data ``(z, y, x)`` and its ``scale`` and ``translate`` in the same
order; slabscope indexes voxels ``[x, y, z]``. The widget turns the layer's data into slabscope's
order (a transposed view, read in place) with its scale as the spacing, and the labels back
into napari's order, with the image layer's scale, translate, rotate, shear and affine, so that
they lie on the image whatever its world transform. Axes in the table are napari's ``(z, y, x)``.

A layer of more than three axes (time, channels: ``(t, z, y, x)``, ``(c, z, y, x)``, ...) is
analysed at the 3D volume napari displays: its last three axes are the volume's ``(z, y, x)``,
its leading ones indexed where the viewer's sliders stand. Its labels are a layer of the same
axes, one long on each leading axis and moved there, so they lie on that volume alone. An RGB
layer is refused.
"""

from __future__ import annotations

import threading
from typing import TYPE_CHECKING, Any, Callable, Optional, Sequence

import numpy as np
import numpy.typing as npt
# napari ships no type information (no py.typed): its names are Any to mypy.
from napari.layers import Image as ImageLayer  # type: ignore[import-untyped]
from napari.qt.threading import FunctionWorker, create_worker  # type: ignore[import-untyped]
from qtpy.QtCore import QObject
from qtpy.QtCore import Signal  # type: ignore[attr-defined]  # qtpy's alias, not re-exported
from qtpy.QtWidgets import (
    QComboBox,
    QHBoxLayout,
    QHeaderView,
    QLabel,
    QProgressBar,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

import slabscope

if TYPE_CHECKING:  # pragma: no cover - for the types only
    import napari  # type: ignore[import-untyped]

__all__ = ["SlabsWidget", "displayed_indices", "labels_placement", "to_napari", "to_slabscope", "volume_of_layer"]

# The progress bar's steps.
_STEPS = 1000


def to_slabscope(data: npt.ArrayLike) -> np.ndarray:
    """A napari layer's 3D data, indexed ``(z, y, x)``, as slabscope's ``[x, y, z]``: a
    transposed view (a C-ordered array becomes a Fortran-ordered one, which slabscope reads in
    place)."""
    return np.transpose(np.asarray(data), (2, 1, 0))


def to_napari(array: npt.ArrayLike) -> np.ndarray:
    """slabscope's ``[x, y, z]`` array (labels, voxels) as napari's ``(z, y, x)``, C-ordered."""
    return np.ascontiguousarray(np.transpose(np.asarray(array), (2, 1, 0)))


def axis_to_napari(axis: Sequence[float]) -> tuple[float, float, float]:
    """An axis ``(x, y, z)`` of slabscope as napari's ``(z, y, x)``."""
    x, y, z = (float(c) for c in axis)
    return (z, y, x)


def volume_of_layer(layer: ImageLayer, at: Sequence[int] = ()) -> slabscope.Volume:
    """The slabscope volume of a single-channel napari image layer: its data (the finest level of
    a multiscale layer) in slabscope's order and its scale as the spacing, in mm. A layer of more
    than three axes gives the 3D volume of its last three at the indices ``at`` of its leading
    ones (``displayed_indices``). A layer of another kind, or ``at`` that does not index its
    leading axes, is a ``ValueError`` naming it."""
    name = layer.name
    if layer.rgb:
        raise ValueError(
            f"layer {name!r} is RGB: slabscope analyses single-channel images "
            "(split its colours into layers of their own first)"
        )
    if layer.ndim < 3:
        raise ValueError(f"layer {name!r} is {layer.ndim}D: slabscope analyses 3D images")
    data = layer.data[0] if layer.multiscale else layer.data
    lead = layer.ndim - 3
    at = tuple(int(i) for i in at)
    if len(at) != lead or any(not 0 <= i < n for i, n in zip(at, data.shape)):
        raise ValueError(
            f"layer {name!r} has data of shape {tuple(data.shape)}: expected {lead} indices of "
            f"its leading axes within it, got {list(at)}"
        )
    spacing = tuple(abs(float(s)) for s in np.asarray(layer.scale)[lead:][::-1])
    return slabscope.Volume.from_array(to_slabscope(data[at] if at else data), spacing=spacing)


def displayed_indices(layer: ImageLayer, viewer: Any) -> tuple[int, ...]:
    """The indices along ``layer``'s leading axes (all but its last three: time, channels...) of
    the 3D volume ``viewer`` displays: the sliders' point in the world mapped into the layer's
    data, rounded and kept within it; ``()`` for a 3D layer."""
    lead = layer.ndim - 3
    if lead <= 0:
        return ()
    point = np.asarray(viewer.dims.point, dtype=float)[-layer.ndim :]
    position = np.asarray(layer.world_to_data(point), dtype=float)
    shape = (layer.data[0] if layer.multiscale else layer.data).shape
    return tuple(int(np.clip(np.rint(position[i]), 0, shape[i] - 1)) for i in range(lead))


def labels_placement(layer: ImageLayer, at: Sequence[int] = ()) -> dict[str, Any]:
    """The placement (``scale``, ``translate``, ``rotate``, ``shear``, ``affine``) of a labels
    layer of ``layer``'s axes, one long on each leading axis, that lies on the 3D volume at the
    indices ``at`` of the leading ones: the layer's own, moved by ``at`` in its data (through its
    scale, rotation and shear, before its affine); the layer's own for a 3D layer."""
    placement = {
        "scale": layer.scale,
        "translate": layer.translate,
        "rotate": layer.rotate,
        "shear": layer.shear,
        "affine": layer.affine,
    }
    if any(at):
        offset = np.zeros(layer.ndim)
        offset[: len(at)] = at
        moved = np.asarray(layer.data_to_world(offset), dtype=float)
        moved -= np.asarray(layer.data_to_world(np.zeros(layer.ndim)), dtype=float)
        # data → world is the affine after translate ∘ rotate ∘ shear ∘ scale: the offset's world
        # step, taken back through the affine's linear part, is the translate's.
        linear = np.asarray(layer.affine.affine_matrix, dtype=float)[:-1, :-1]
        placement["translate"] = np.asarray(layer.translate, dtype=float) + np.linalg.solve(linear, moved)
    return placement


class _Cancelled(Exception):
    """Raised from the progress callback to stop a run the user cancelled, with the phase it
    stopped in (None when the run had ended first)."""

    def __init__(self, phase: Optional[str]) -> None:
        super().__init__(phase)
        self.phase = phase


class _Signals(QObject):
    """Progress from the worker thread, delivered in the widget's thread."""

    progressed = Signal(str, float)


class SlabsWidget(QWidget):
    """The dock widget: pick an image layer, analyse it (``options`` are ``analyze``'s
    keywords, empty by default: the CLI's defaults), see the ranking, add the exploded view."""

    def __init__(self, napari_viewer: napari.viewer.Viewer, parent: Optional[QWidget] = None) -> None:
        super().__init__(parent)
        self.viewer = napari_viewer
        self.options: dict[str, Any] = {}
        self.analysis: Optional[slabscope.Analysis] = None
        self.labels_layer: Optional[Any] = None
        self.view_layer: Optional[Any] = None
        self.worker: Optional[FunctionWorker] = None
        self._cancel: Optional[threading.Event] = None
        # The phase the last cancelled run stopped in (None: it had ended when cancelled).
        self.cancelled_in: Optional[str] = None
        self._source: Optional[ImageLayer] = None
        self._volume: Optional[slabscope.Volume] = None
        self._signals = _Signals()
        self._signals.progressed.connect(self._progressed)

        self.layer_box = QComboBox()
        self.run_button = QPushButton("Analyse")
        self.cancel_button = QPushButton("Cancel")
        self.view_button = QPushButton("Add exploded view")
        self.progress = QProgressBar()
        self.progress.setRange(0, _STEPS)
        self.status = QLabel("")
        self.status.setWordWrap(True)
        self.table = QTableWidget(0, 3)
        self.table.setHorizontalHeaderLabels(["axis (z, y, x)", "entropy rate", "mean over phases"])
        header = self.table.horizontalHeader()
        if header is not None:
            # Each column as wide as its header and its cells, never cut by a narrow dock.
            header.setSectionResizeMode(QHeaderView.ResizeToContents)
        self.cancel_button.setEnabled(False)
        self.view_button.setEnabled(False)

        buttons = QHBoxLayout()
        buttons.addWidget(self.run_button)
        buttons.addWidget(self.cancel_button)
        layout = QVBoxLayout()
        layout.addWidget(QLabel("Image layer"))
        layout.addWidget(self.layer_box)
        layout.addLayout(buttons)
        layout.addWidget(self.progress)
        layout.addWidget(self.status)
        layout.addWidget(QLabel("Views, best first"))
        layout.addWidget(self.table)
        layout.addWidget(self.view_button)
        self.setLayout(layout)
        self._fit_table()

        self.run_button.clicked.connect(self.run)
        self.cancel_button.clicked.connect(self.cancel)
        self.view_button.clicked.connect(self.add_exploded_view)
        events = self.viewer.layers.events
        for event in (events.inserted, events.removed, events.reordered):
            event.connect(self._refresh_layers)
        self._refresh_layers()

    # The layers offered.

    def image_layers(self) -> list[ImageLayer]:
        """The viewer's image layers of three axes or more (a 4D one is analysed at the 3D
        volume displayed; an RGB one is refused when analysed, saying why)."""
        return [layer for layer in self.viewer.layers if isinstance(layer, ImageLayer) and layer.ndim >= 3]

    def _refresh_layers(self, event: Any = None) -> None:
        current = self.layer_box.currentText()
        names = [layer.name for layer in self.image_layers()]
        self.layer_box.clear()
        self.layer_box.addItems(names)
        active = self.viewer.layers.selection.active
        for wanted in (current, getattr(active, "name", None)):
            if wanted in names:
                self.layer_box.setCurrentIndex(names.index(wanted))

    def selected_layer(self) -> Optional[ImageLayer]:
        """The image layer picked in the widget."""
        name = self.layer_box.currentText()
        for layer in self.image_layers():
            if layer.name == name:
                return layer
        return None

    # The analysis, in a worker thread.

    def run(self) -> None:
        """Analyses the picked layer in a worker thread; the labels and the table follow."""
        layer = self.selected_layer()
        if layer is None:
            self.status.setText("No 3D image layer to analyse.")
            return
        try:
            at = displayed_indices(layer, self.viewer)
            volume = volume_of_layer(layer, at)
        except (ValueError, slabscope.VolumeError) as e:
            self.status.setText(str(e))
            return
        cancel, progress = self._reporter()
        options = dict(self.options)

        def work() -> tuple[slabscope.Analysis, np.ndarray]:
            analysis = slabscope.analyze(volume, progress=progress, **options)
            if cancel.is_set():
                raise _Cancelled(None)
            return analysis, to_napari(analysis.labels())

        self._start(work, lambda done: self._analysed(layer, at, volume, *done), cancel)
        self.status.setText(f"Analysing {_volume_shown(layer, at)}…")

    def _reporter(self) -> tuple[threading.Event, Callable[[str, float], None]]:
        """A run's cancel flag and its progress callback, which reports to the widget and stops
        the run at its next report once the flag is set."""
        cancel = threading.Event()
        signals = self._signals

        def progress(phase: str, fraction: float) -> None:
            if cancel.is_set():
                raise _Cancelled(phase)
            signals.progressed.emit(phase, fraction)

        return cancel, progress

    def _start(
        self, work: Callable[[], Any], done: Callable[[Any], None], cancel: threading.Event
    ) -> None:
        self._cancel = cancel
        self.progress.setValue(0)
        worker = create_worker(work, _start_thread=False, _ignore_errors=True)
        worker.returned.connect(done)
        worker.errored.connect(self._failed)
        worker.finished.connect(self._finished)
        self.worker = worker
        self.run_button.setEnabled(False)
        self.view_button.setEnabled(False)
        self.cancel_button.setEnabled(True)
        worker.start()

    def cancel(self) -> None:
        """Stops the run under way (at its next progress report)."""
        if self._cancel is not None:
            self._cancel.set()
            self.status.setText("Cancelling…")

    def _progressed(self, phase: str, fraction: float) -> None:
        self.progress.setValue(round(fraction * _STEPS))
        self.progress.setFormat(f"{phase} %p%")

    def _failed(self, error: BaseException) -> None:
        if isinstance(error, _Cancelled):
            self.cancelled_in = error.phase
            self.status.setText("Cancelled.")
        else:
            self.status.setText(f"Failed: {error}")

    def _finished(self) -> None:
        self.worker = None
        self._cancel = None
        self.run_button.setEnabled(True)
        self.cancel_button.setEnabled(False)
        self.view_button.setEnabled(self.analysis is not None)

    def _analysed(
        self,
        layer: ImageLayer,
        at: tuple[int, ...],
        volume: slabscope.Volume,
        analysis: slabscope.Analysis,
        labels: np.ndarray,
    ) -> None:
        self.analysis, self._source, self._volume = analysis, layer, volume
        self.progress.setValue(_STEPS)
        name = f"{layer.name} slabs"
        if name in self.viewer.layers:
            self.viewer.layers.remove(name)
        # The image's own placement in the world (moved to the volume analysed along its leading
        # axes), so that the labels lie on it.
        self.labels_layer = self.viewer.add_labels(
            labels.reshape((1,) * len(at) + labels.shape), name=name, **labels_placement(layer, at)
        )
        self.fill_table(analysis)
        slabs = len(analysis.slabs)
        where = f" of {_volume_shown(layer, at)}" if at else ""
        self.status.setText(
            f"{slabs} slabs across axis {_shown(axis_to_napari(analysis.best_axis))} (z, y, x){where}."
        )

    def fill_table(self, analysis: slabscope.Analysis) -> None:
        """One row a view, best first, as ``analysis.views`` ranks them: its axis, its entropy
        rate on the paper's lattice, and the mean over lattice phases the defaults rank by
        (a dash by the paper's method, which ranks by the entropy rate)."""
        views = list(analysis.views)
        self.table.setRowCount(len(views))
        for row, view in enumerate(views):
            cells = (
                _shown(axis_to_napari(view["axis"])),
                f"{view['entropy_rate']:.4f}",
                _phase_mean(view),
            )
            for column, text in enumerate(cells):
                self.table.setItem(row, column, QTableWidgetItem(text))
        self._fit_table()

    def _fit_table(self) -> None:
        """Sizes the columns to their headers and cells, and keeps the table (so the dock) at
        least as wide as they are together, so that no header or cell is cut."""
        self.table.resizeColumnsToContents()
        header, rows = self.table.horizontalHeader(), self.table.verticalHeader()
        if header is None or rows is None:
            return
        columns = sum(header.sectionSize(c) for c in range(self.table.columnCount()))
        scroll = self.table.verticalScrollBar()
        extra = rows.sizeHint().width() + 2 * self.table.frameWidth()
        extra += scroll.sizeHint().width() if scroll is not None else 0
        self.table.setMinimumWidth(columns + extra)

    def add_exploded_view(self) -> None:
        """Adds the exploded view of the last analysis as an RGB image layer (drawn in a worker
        thread)."""
        analysis, volume, layer = self.analysis, self._volume, self._source
        if analysis is None or volume is None or layer is None:
            self.status.setText("Analyse a layer first.")
            return
        cancel, progress = self._reporter()
        options = dict(self.options)

        def work() -> np.ndarray:
            image = slabscope.render(volume, analysis, progress=progress, **_render_options(options))
            return np.asarray(image)

        def done(pixels: np.ndarray) -> None:
            self.view_layer = self.viewer.add_image(pixels, rgb=True, name=f"{layer.name} exploded view")
            self.status.setText("Exploded view added.")

        self._start(work, done, cancel)
        self.status.setText("Drawing the exploded view…")


def _render_options(options: dict[str, Any]) -> dict[str, Any]:
    """The keywords of ``options`` that ``render`` takes (its own and the look's)."""
    keywords = {p["keyword"] for p in slabscope.parameters("render")}
    return {k: v for k, v in options.items() if k in keywords}


def _volume_shown(layer: ImageLayer, at: Sequence[int]) -> str:
    """The volume analysed of ``layer``: its name, and for a layer of more than three axes the
    3D volume displayed, as NumPy indexes its data."""
    if not at:
        return str(layer.name)
    index = ", ".join([str(i) for i in at] + [":"] * 3)
    return f"{layer.name}, the 3D volume displayed: data[{index}] of its {layer.ndim}D data"


def _phase_mean(view: dict[str, Any]) -> str:
    """The mean entropy rate over lattice phases a view was ranked by, or a dash when the
    analysis ran on the paper's lattice alone."""
    phases = view.get("phases")
    return f"{phases['mean']:.4f}" if isinstance(phases, dict) else "–"


def _shown(axis: Sequence[float]) -> str:
    return "(" + ", ".join(f"{c:+.3f}" for c in axis) + ")"
