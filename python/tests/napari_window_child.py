"""Run by test_napari_window.py in a real napari window on an X server (Xvfb): docks the plugin
found through its npe2 manifest, analyses an image layer, and reports, for planes of the layer,
where the canvas draws the image and where it draws the labels."""

import json
import sys
import time

import napari
import numpy as np
from qtpy.QtWidgets import QApplication

# A (z, y, x) volume: four layers along z inside a dark frame, with a little noise.
rng = np.random.default_rng(3)
nz, ny, nx = 32, 40, 48
data = np.zeros((nz, ny, nx), np.float32)
z = np.arange(nz)[:, None, None]
inner = (slice(None), slice(8, 32), slice(10, 38))
data[inner] = (100.0 + 30.0 * (z * 4 // nz) + rng.normal(0.0, 2.0, (nz, ny, nx)))[inner]

viewer = napari.Viewer(show=True)
image = viewer.add_image(data, name="img", scale=(2.0, 0.5, 0.75), translate=(10.0, -5.0, 3.0))
# The dock widget as napari's Plugins menu opens it: by the manifest's plugin and widget names.
_, widget = viewer.window.add_plugin_dock_widget("slabscope", "Slabs (exploded view)")
widget.run()
app = QApplication.instance()
deadline = time.monotonic() + 120
while widget.worker is not None and time.monotonic() < deadline:
    app.processEvents()
    time.sleep(0.01)
labels = viewer.layers["img slabs"]
labels.opacity = 1.0
viewer.dims.ndisplay = 2
viewer.reset_view()


def shot(show):
    image.visible, labels.visible = show == "image", show == "labels"
    app.processEvents()
    return viewer.screenshot(canvas_only=True, flash=False)[..., :3].astype(int)


planes = []
for k in (1, 12, 20, 30):
    viewer.dims.set_point(0, float(image.data_to_world([k, 0, 0])[0]))
    img, lab = shot("image"), shot("labels")
    expected = sorted({int(v) for v in np.unique(labels.data[k])} - {0})
    drawn = lab.max(axis=-1) > 0
    colours, counts = np.unique(lab[drawn], axis=0, return_counts=True)
    planes.append(
        {
            "plane": k,
            "bright": int((img.max(axis=-1) > 60).sum()),
            "drawn": int(drawn.sum()),
            "both": int(((img.max(axis=-1) > 60) & drawn).sum()),
            "labels": expected,
            "colour": [int(c) for c in colours[np.argmax(counts)]] if len(counts) else None,
            "label_colours": {
                str(v): [round(255 * float(c)) for c in labels.get_color(v)[:3]] for v in expected
            },
        }
    )
print(json.dumps({"status": widget.status.text(), "planes": planes}))
viewer.close()
sys.exit(0)
