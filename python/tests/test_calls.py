"""Long calls: the GIL released, progress reported, Ctrl-C honoured; files: errors as Python
exceptions with one-line messages, hostile fixtures never crash the interpreter; pictures."""

from __future__ import annotations

import _thread
import threading
import time

import numpy as np
import pytest

import slabscope

from conftest import BAD, DATA

PNG = b"\x89PNG\r\n\x1a\n"


def test_other_threads_run_during_an_analysis(phantoms):
    volume = slabscope.load(str(phantoms["big"]))
    ticks = 0
    done = threading.Event()

    def count():
        nonlocal ticks
        while not done.is_set():
            ticks += 1
            time.sleep(0.001)

    counter = threading.Thread(target=count)
    counter.start()
    started = time.perf_counter()
    slabscope.analyze(volume, level=2)
    took = time.perf_counter() - started
    done.set()
    counter.join()
    # With the GIL held throughout, the counter would not tick at all until the call returned.
    assert ticks > 0.3 * took / 0.0011, (ticks, took)


def test_progress_reaches_the_callback_in_order(phantoms):
    seen = []
    slabscope.analyze(slabscope.load(str(phantoms["body"])), progress=lambda phase, f: seen.append((phase, f)))
    assert seen, "progress was reported"
    phases = [p for p, _ in seen]
    assert "view search" in phases
    for (p, f), (q, g) in zip(seen, seen[1:]):
        assert 0.0 <= f <= 1.0
        if p == q:
            assert g >= f, seen


def test_an_exception_in_the_callback_stops_the_call(phantoms):
    def fail(phase, fraction):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        slabscope.analyze(slabscope.load(str(phantoms["big"])), progress=fail)


def test_ctrl_c_stops_a_long_search_within_a_second(phantoms):
    volume = slabscope.load(str(phantoms["big"]))
    timer = threading.Timer(0.5, _thread.interrupt_main)
    started = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        slabscope.analyze(volume, level=4, phases=64, phase_subset=1, refine=True)
    assert time.perf_counter() - started < 1.5


def _crc32c(data: bytes) -> int:
    table = []
    for i in range(256):
        c = i
        for _ in range(8):
            c = (c >> 1) ^ 0x82F63B78 if c & 1 else c >> 1
        table.append(c)
    c = 0xFFFFFFFF
    for byte in data:
        c = table[(c ^ byte) & 0xFF] ^ (c >> 8)
    return c ^ 0xFFFFFFFF


def _one_shard_of_tiny_chunks(path, n=40):
    """A Zarr v3 array of n³ u8 in one shard of one-voxel inner chunks, none written: n³ reads
    of the shard's index, a minute's load, under the chunk-flood limit (64,000 for n=40)."""
    (path / "c" / "0" / "0").mkdir(parents=True)
    bytes_codec = '{"name": "bytes", "configuration": {"endian": "little"}}'
    (path / "zarr.json").write_text(
        '{"zarr_format": 3, "node_type": "array", "shape": [%d, %d, %d], "data_type": "uint8",'
        ' "fill_value": 0, "chunk_grid": {"name": "regular", "configuration": {"chunk_shape":'
        ' [%d, %d, %d]}}, "chunk_key_encoding": {"name": "default", "configuration":'
        ' {"separator": "/"}}, "codecs": [{"name": "sharding_indexed", "configuration":'
        ' {"chunk_shape": [1, 1, 1], "codecs": [%s], "index_codecs": [%s, {"name": "crc32c"}],'
        ' "index_location": "end"}}]}' % (n, n, n, n, n, n, bytes_codec, bytes_codec)
    )
    index = b"\xff" * (16 * n**3)
    (path / "c" / "0" / "0" / "0").write_bytes(index + _crc32c(index).to_bytes(4, "little"))
    return path


def test_ctrl_c_stops_a_long_load_within_a_second(tmp_path):
    store = _one_shard_of_tiny_chunks(tmp_path / "slow.zarr")
    timer = threading.Timer(0.5, _thread.interrupt_main)
    started = time.perf_counter()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        slabscope.load(str(store))
    assert time.perf_counter() - started < 1.5


@pytest.mark.parametrize("name", sorted(p.name for p in BAD.iterdir() if p.name != "make_corpus.py"))
def test_every_hostile_fixture_is_an_exception(name):
    with pytest.raises((slabscope.VolumeError, OSError, ValueError)) as raised:
        slabscope.analyze(slabscope.load(str(BAD / name)))
    message = str(raised.value)
    assert "\n" not in message and message, message


def test_files_errors_are_the_exceptions_users_catch(tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere.nii"):
        slabscope.load(str(tmp_path / "nowhere.nii"))
    with pytest.raises(slabscope.VolumeError, match=r"not a volume file"):
        slabscope.load(str(BAD / "not_a_volume.txt"))
    raw = tmp_path / "data.raw"
    raw.write_bytes(bytes(64))
    with pytest.raises(slabscope.VolumeError, match=r"give dims=\(NX, NY, NZ\)"):
        slabscope.load(str(raw))
    volume = slabscope.load(raw, dims=(4, 4, 4), dtype=np.uint8)
    assert volume.shape == (4, 4, 4) and volume.format == "raw"
    gz = str(DATA / "ramp_u8_two_members.nii.gz")
    with pytest.raises(
        slabscope.VolumeError,
        match=r"raise it with max_memory=, or decode it to disk with scratch=\)$",
    ):
        slabscope.load(gz, max_memory=10)
    # Decoded into an unnamed file of the scratch folder instead: the same voxels, mapped.
    (tmp_path / "scratch").mkdir()
    decoded = slabscope.load(gz, max_memory=10, scratch=str(tmp_path / "scratch"))
    np.testing.assert_array_equal(decoded.array, slabscope.load(gz).array)
    assert list((tmp_path / "scratch").iterdir()) == []
    with pytest.raises(TypeError, match="unexpected keyword argument 'dim'"):
        slabscope.load(raw, dim=(4, 4, 4))


def test_render_and_slice_give_rgba_pictures_a_notebook_shows(phantoms, tmp_path):
    volume = slabscope.load(str(phantoms["body"]))
    analysis = slabscope.analyze(volume)
    image = slabscope.render(volume, analysis, size=(320, 240), azimuth=45)
    assert image.size == (320, 240)
    assert image.array.shape == (240, 320, 4) and image.array.dtype == np.uint8
    assert (image.array[..., 3] == 255).all(), "opaque"
    assert image._repr_png_().startswith(PNG)
    assert len(np.unique(image.array[..., :3].reshape(-1, 3), axis=0)) > 50, "a picture, not a blank"
    cut = slabscope.slice(volume, analysis, size=(128, 128))
    assert cut.array.shape[2] == 4 and max(cut.size) == 128
    out = tmp_path / "view.png"
    image.save(out)
    assert out.read_bytes() == image.png()
    with pytest.raises(FileExistsError, match="force=True"):
        image.save(out)
    image.save(out, force=True)
    with pytest.raises(ValueError, match=r"pictures are written as \.png, \.jpg or \.jpeg"):
        image.save(phantoms["body"], force=True)
    with pytest.raises(ValueError, match="highlight=9"):
        slabscope.render(volume, analysis, highlight=9)
    other = slabscope.load(str(phantoms["layers"]))
    with pytest.raises(ValueError, match="another volume"):
        slabscope.render(other, analysis)
    # The same file read again is the same voxels and geometry: its analysis draws it.
    again = slabscope.load(str(phantoms["body"]))
    assert slabscope.render(again, analysis, size=(64, 48)).png() == slabscope.render(volume, analysis, size=(64, 48)).png()


def test_render_matches_the_cli_picture(phantoms, cli, tmp_path):
    path = str(phantoms["body"])
    out = tmp_path / "cli.png"
    cli("render", path, "-o", str(out), "--size", "200x150", "--mode", "mip")
    ours = slabscope.render(slabscope.load(path), size=(200, 150), mode="mip")
    assert ours.png() == out.read_bytes()


def test_render_faces_matches_the_cli_picture(phantoms, cli, tmp_path):
    path = str(phantoms["body"])
    out = tmp_path / "faces.png"
    cli("render", path, "-o", str(out), "--faces", "--slabs", "3", "--size", "300x160", "--colormap", "bone")
    volume = slabscope.load(path)
    analysis = slabscope.analyze(volume, slabs=3)
    faces = slabscope.render(volume, analysis, faces=True, size=(300, 160), colormap="bone")
    assert faces.png() == out.read_bytes()
    # Three columns of 94-pixel tiles and two rows of 74, with 4-pixel gaps: not the exploded view.
    assert faces.size == (298, 160)
    assert faces.png() != slabscope.render(volume, analysis, size=(300, 160), colormap="bone").png()
    with pytest.raises(ValueError, match=r"^size=\(30, 30\): too small for the faces of 3 slabs$"):
        slabscope.render(volume, analysis, faces=True, size=(30, 30))


def test_an_ome_zarr_store_and_its_label_image():
    store = DATA / "zarr" / "v05_sharded.ome.zarr"
    image = slabscope.load(store)
    assert image.format == "ome-zarr"
    assert image.shape == (11, 10, 9)
    assert image.spacing == (1.0, 1.0, 1.5)
    cells = slabscope.load(store, label_image="cells")
    assert cells.dtype == "uint8"
    assert cells.array.max() == 4
    with pytest.raises(slabscope.VolumeError, match='no label image "nuclei"'):
        slabscope.load(store, label_image="nuclei")
    timed = slabscope.load(DATA / "zarr" / "v05_tczyx.ome.zarr", channel=2, volume=1)
    assert timed.notes == [
        "OME-Zarr image of 3 channels and 2 time points: read channel 2 at time point 1"
    ]


def test_an_ome_zarr_store_at_a_url_is_read_in_place():
    import functools
    import http.server

    handler = functools.partial(
        http.server.SimpleHTTPRequestHandler, directory=str(DATA / "zarr")
    )
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        url = f"http://127.0.0.1:{server.server_address[1]}/v05_sharded.ome.zarr"
        remote = slabscope.load(url)
        local = slabscope.load(DATA / "zarr" / "v05_sharded.ome.zarr")
        assert remote.shape == local.shape
        assert remote.spacing == local.spacing
        assert np.array_equal(remote.array, local.array)
        cells = slabscope.load(url, label_image="cells")
        assert cells.array.max() == 4
        with pytest.raises(slabscope.VolumeError, match="no Zarr store at this URL"):
            slabscope.load(url.replace("v05_sharded", "absent"))
    finally:
        server.shutdown()


def test_an_ome_tiffs_channel_and_time_point_are_keywords():
    volume = slabscope.load(DATA / "ome" / "zct.ome.tif", channel=1, volume=1)
    assert volume.range == (4000.0, 4234.0)
    assert volume.notes == ["OME-TIFF of 2 channels and 2 time points: read channel 1 at time point 1"]
    assert volume.spacing == pytest.approx((0.0005, 0.00025, 0.002))
    with pytest.raises(slabscope.VolumeError, match="holds 2 channels .* no channel 2"):
        slabscope.load(DATA / "ome" / "zct.ome.tif", channel=2)


def test_a_star_import_leaves_the_builtin_slice_alone():
    scope: dict = {}
    exec("from slabscope import *", scope)
    assert "slice" not in scope and "load" in scope and "triage_frame" in scope
    assert "slice" not in slabscope.__all__
    from slabscope import slice as picture_slice

    assert picture_slice is slabscope.slice
    # The package's function lists its keywords (its signature) and calls the extension's.
    assert slabscope.slice.__wrapped__ is slabscope._slabscope.slice
    assert all(hasattr(slabscope, name) for name in slabscope.__all__)
