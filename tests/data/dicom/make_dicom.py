#!/usr/bin/env python3
"""Writes the DICOM fixtures of tests/dicom.rs (pydicom 3; dcmtk's dcmcjpeg for JPEG lossless;
OpenJPEG through pylibjpeg-openjpeg for JPEG 2000, libjxl through imagecodecs for JPEG XL).

Every image holds the same known values, so that the tests can check the assembled volumes
voxel by voxel without reading anything but the DICOM files:

    stored(i, j, k) = (3*i + 5*j + 11*k) % 1000      (i column, j row, k slice along the normal)

Every file carries made-up patient details (PATIENT_* below) that must never appear in any
output unless --show-phi is given.

Run from the repository root:  python3 tests/data/dicom/make_dicom.py [FUNCTION...]
(pip install pydicom pylibjpeg pylibjpeg-openjpeg imagecodecs numpy; dcmtk for JPEG lossless)
"""

import hashlib
import math
import os
import shutil
import subprocess
import sys

import numpy as np
import pydicom
from pydicom.dataset import Dataset, FileMetaDataset
from pydicom.sequence import Sequence
from pydicom.uid import (
    DeflatedExplicitVRLittleEndian,
    ExplicitVRLittleEndian,
    ImplicitVRLittleEndian,
    JPEG2000,
    JPEG2000Lossless,
    JPEGLSLossless,
    generate_uid,
)

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)))
COLS, ROWS = 24, 20
PATIENT_NAME = "Zebedee^Quintessa"
PATIENT_ID = "PID-73125-QX"
BIRTH = "19370412"
ADDRESS = "12 Lindenhof Lane, Quarryburgh"
ACCESSION = "ACC9911037"
ROOT = "1.2.826.0.1.3680043.8.498."


def uid(name):
    """A stable UID for a name (fixtures stay byte-identical between runs)."""
    digest = int(hashlib.sha1(name.encode()).hexdigest()[:24], 16)
    return ROOT + str(digest)


def stored(k, cols=COLS, rows=ROWS):
    j, i = np.mgrid[0:rows, 0:cols]
    return (3 * i + 5 * j + 11 * k) % 1000


def base(series, number, description, modality="CT"):
    ds = Dataset()
    ds.PatientName = PATIENT_NAME
    ds.PatientID = PATIENT_ID
    ds.PatientBirthDate = BIRTH
    ds.PatientAddress = ADDRESS
    ds.AccessionNumber = ACCESSION
    ds.StudyDate = "20240229"
    ds.Modality = modality
    ds.StudyInstanceUID = uid("study")
    ds.SeriesInstanceUID = uid(series)
    ds.SeriesNumber = number
    ds.SeriesDescription = description
    ds.FrameOfReferenceUID = uid("frame")
    ds.SOPClassUID = "1.2.840.10008.5.1.4.1.1.2"
    return ds


def image(ds, pixels, signed=True, bits=16, stored_bits=None, photometric="MONOCHROME2"):
    ds.Rows, ds.Columns = pixels.shape
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = photometric
    ds.BitsAllocated = bits
    ds.BitsStored = stored_bits or bits
    ds.HighBit = ds.BitsStored - 1
    ds.PixelRepresentation = 1 if signed else 0
    dtype = {(16, True): "<i2", (16, False): "<u2", (8, False): "u1"}[(bits, signed)]
    ds.PixelData = pixels.astype(dtype).tobytes()


def save(ds, path, syntax=ExplicitVRLittleEndian, sop=None):
    ds.SOPInstanceUID = sop or uid(path)
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = ds.SOPClassUID
    meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
    meta.TransferSyntaxUID = syntax
    ds.file_meta = meta
    os.makedirs(os.path.dirname(path), exist_ok=True)
    ds.save_as(path, enforce_file_format=True)


def slice_at(series, number, description, k, position, orientation=(1, 0, 0, 0, 1, 0),
             spacing=(0.7, 0.8), instance=None):
    ds = base(series, number, description)
    ds.ImageType = ["ORIGINAL", "PRIMARY", "AXIAL"]
    ds.InstanceNumber = instance if instance is not None else k + 1
    ds.ImagePositionPatient = [f"{v:.4f}" for v in position]
    ds.ImageOrientationPatient = list(orientation)
    ds.PixelSpacing = list(spacing)
    ds.SliceThickness = 5.0  # deliberately not the spacing between slices
    ds.RescaleSlope = 1
    ds.RescaleIntercept = -1024
    image(ds, stored(k))
    return ds


def fresh(name):
    """The fixture folder `name`, emptied."""
    d = os.path.join(OUT, name)
    shutil.rmtree(d, ignore_errors=True)
    return d


def shuffled_name(series, k):
    return "IM" + hashlib.sha1(f"{series}-{k}".encode()).hexdigest()[:8].upper()


def ct_folder():
    """Series 3 (12 axial slices 2.5 mm apart, shuffled file names, instance numbers reversed),
    series 4 (6 sagittal slices), and a localizer, in one folder."""
    d = fresh("ct")
    for k in range(12):
        ds = slice_at("ct", 3, "Abdomen 2.5", k, (-8.0, -6.0, 40.0 + 2.5 * k), instance=12 - k)
        save(ds, os.path.join(d, shuffled_name("ct", k)))
    for k in range(6):
        # Sagittal: rows along -z (feet down), columns along y; the normal is x.
        ds = slice_at("sag", 4, "Sagittal MPR", k, (3.0 * k, -6.0, 60.0),
                      orientation=(0, 1, 0, 0, 0, -1))
        save(ds, os.path.join(d, shuffled_name("sag", k)))
    loc = slice_at("loc", 1, "Topogram", 0, (-8.0, 0.0, 100.0), orientation=(1, 0, 0, 0, 0, -1))
    loc.ImageType = ["ORIGINAL", "PRIMARY", "LOCALIZER"]
    save(loc, os.path.join(d, "LOCALIZER"))


def gap_folder():
    """Implicit VR little endian; 8 positions 2 mm apart with the slice at k = 5 missing."""
    d = fresh("gap")
    for k in range(8):
        if k == 5:
            continue
        ds = slice_at("gap", 5, "Gap", k, (0.0, 0.0, 2.0 * k))
        save(ds, os.path.join(d, f"slice{k:02d}.dcm"), syntax=ImplicitVRLittleEndian)


def tilt_folder():
    """Gantry tilt of 15 degrees: each slice 3 mm up and 3*tan(15°) mm along y."""
    d = fresh("tilt")
    t = math.tan(math.radians(15.0))
    for k in range(8):
        ds = slice_at("tilt", 6, "Tilted head", k, (0.0, 3.0 * t * k, 3.0 * k))
        ds.GantryDetectorTilt = 15.0
        save(ds, os.path.join(d, f"t{k}.dcm"))


def mono1_folder():
    """MONOCHROME1, unsigned, 12 bits stored in 16."""
    d = fresh("mono1")
    for k in range(4):
        ds = slice_at("mono1", 7, "Inverted", k, (0.0, 0.0, 1.5 * k))
        del ds.RescaleSlope
        del ds.RescaleIntercept
        image(ds, stored(k), signed=False, stored_bits=12, photometric="MONOCHROME1")
        save(ds, os.path.join(d, f"m{k}.dcm"))


def rescale_folder():
    """Rescale slope and intercept that change from slice to slice."""
    d = fresh("rescale")
    for k in range(5):
        ds = slice_at("rescale", 8, "Rescaled", k, (0.0, 0.0, 2.0 * k))
        ds.RescaleSlope = f"{0.5 * (k + 1):g}"
        ds.RescaleIntercept = f"{-100 * k}"
        save(ds, os.path.join(d, f"r{k}.dcm"))


def fourd_folder():
    """Four positions, each acquired twice (temporal positions 1 and 2): a 4D series. The second
    time point's values are the first's plus 500."""
    d = fresh("fourd")
    for t in range(2):
        for k in range(4):
            ds = slice_at("fourd", 9, "Dynamic", k, (0.0, 0.0, 4.0 * k), instance=t * 4 + k + 1)
            ds.TemporalPositionIdentifier = t + 1
            image(ds, stored(k) + 500 * t)
            save(ds, os.path.join(d, f"d{t}{k}.dcm"))


def enhanced_file():
    """An enhanced MR multi-frame file: 6 frames stored in reverse order of position, orientation
    and pixel measures shared, position and rescale per frame."""
    ds = base("enhanced", 10, "Enhanced T1", modality="MR")
    ds.SOPClassUID = "1.2.840.10008.5.1.4.1.1.4.1"
    ds.ImageType = ["ORIGINAL", "PRIMARY", "M", "NONE"]
    ds.InstanceNumber = 1
    n = 6
    ds.NumberOfFrames = n
    shared = Dataset()
    orient = Dataset()
    orient.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
    shared.PlaneOrientationSequence = Sequence([orient])
    measures = Dataset()
    measures.PixelSpacing = [0.9, 0.9]
    measures.SliceThickness = 1.2
    shared.PixelMeasuresSequence = Sequence([measures])
    ds.SharedFunctionalGroupsSequence = Sequence([shared])
    frames = []
    data = []
    for f in range(n):
        k = n - 1 - f
        item = Dataset()
        pos = Dataset()
        pos.ImagePositionPatient = [0.0, 0.0, 1.2 * k]
        item.PlanePositionSequence = Sequence([pos])
        value = Dataset()
        value.RescaleSlope = 2
        value.RescaleIntercept = k
        value.RescaleType = "US"
        item.PixelValueTransformationSequence = Sequence([value])
        frames.append(item)
        data.append(stored(k))
    ds.PerFrameFunctionalGroupsSequence = Sequence(frames)
    image(ds, np.stack(data)[0], signed=False)
    ds.PixelData = np.stack(data).astype("<u2").tobytes()
    save(ds, os.path.join(OUT, "enhanced.dcm"))


def deflated_file():
    """One slice in deflated explicit VR little endian."""
    ds = slice_at("deflate", 11, "Deflated", 0, (0.0, 0.0, 0.0))
    save(ds, os.path.join(OUT, "deflated.dcm"), syntax=DeflatedExplicitVRLittleEndian)


def no_preamble_file():
    """One slice written without the 128-byte preamble: the file starts with DICM."""
    ds = slice_at("nopre", 12, "No preamble", 0, (0.0, 0.0, 0.0))
    path = os.path.join(OUT, "nopreamble.dcm")
    save(ds, path)
    with open(path, "rb") as f:
        data = f.read()
    with open(path, "wb") as f:
        f.write(data[128:])


def unsupported_file():
    """A file whose transfer syntax is JPEG-LS (the fragment is not real JPEG-LS)."""
    ds = slice_at("jls", 13, "JPEG-LS", 0, (0.0, 0.0, 0.0))
    from pydicom.encaps import encapsulate
    ds.PixelData = encapsulate([b"\xff\xd8\xff\xf7" + bytes(60)])
    ds["PixelData"].VR = "OB"
    save(ds, os.path.join(OUT, "jpegls.dcm"), syntax=JPEGLSLossless)


def j2k_folders():
    """Series 15 and 16: three slices of 64x64 pixels each compressed to JPEG 2000 by OpenJPEG
    (through pydicom's pylibjpeg plugin), lossless and lossy (a compression ratio of 50, errors
    of up to about 70). `j2k-lossy/expected.raw` is the lossy series as OpenJPEG decodes it
    (little-endian i16 stored values, slice after slice), for a test that allows a difference
    of 1 between decoders."""
    from pydicom.pixels import pixel_array

    for name, number, syntax, kwargs in [
        ("j2k-lossless", 15, JPEG2000Lossless, {}),
        ("j2k-lossy", 16, JPEG2000, {"compression_ratios": [50]}),
    ]:
        d = fresh(name)
        decoded = []
        for k in range(3):
            ds = slice_at(name, number, name, k, (0.0, 0.0, 2.0 * k))
            image(ds, stored(k, 64, 64))  # OpenJPEG's encoder needs more than 24x20 pixels
            ds.file_meta = FileMetaDataset()
            ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
            ds.compress(syntax, encoding_plugin="pylibjpeg", **kwargs)
            path = os.path.join(d, f"s{k}.dcm")
            save(ds, path, syntax=syntax)
            decoded.append(pixel_array(path, decoding_plugin="pylibjpeg").astype("<i2"))
        if syntax == JPEG2000:
            with open(os.path.join(d, "expected.raw"), "wb") as f:
                f.write(np.stack(decoded).tobytes())
        else:
            assert all((a == stored(k, 64, 64)).all() for k, a in enumerate(decoded)), name


def jxl_folders():
    """Series 17 and 18: three unsigned slices of 64x64 pixels each compressed to a bare JPEG XL
    codestream by libjxl (through imagecodecs), lossless and lossy (distance 4).
    `jxl-lossy/expected.raw` is the lossy series as libjxl decodes it (little-endian u16 stored
    values, slice after slice)."""
    import imagecodecs
    from pydicom.encaps import encapsulate

    for name, number, syntax, kwargs in [
        ("jxl-lossless", 17, "1.2.840.10008.1.2.4.110", {"lossless": True}),
        ("jxl-lossy", 18, "1.2.840.10008.1.2.4.112", {"distance": 4.0}),
    ]:
        d = fresh(name)
        os.makedirs(d)
        decoded = []
        for k in range(3):
            ds = slice_at(name, number, name, k, (0.0, 0.0, 2.0 * k))
            pixels = stored(k, 64, 64).astype("<u2")
            image(ds, pixels, signed=False)
            code = imagecodecs.jpegxl_encode(pixels, usecontainer=False, **kwargs)
            ds.PixelData = encapsulate([code])
            ds["PixelData"].VR = "OB"
            ds["PixelData"].is_undefined_length = True
            # pydicom 3.0 does not know JPEG XL's UIDs, so the file is written piece by piece.
            hand_written(ds, os.path.join(d, f"s{k}.dcm"), syntax, implicit=False)
            decoded.append(imagecodecs.jpegxl_decode(code).astype("<u2"))
        if "distance" in kwargs:
            with open(os.path.join(d, "expected.raw"), "wb") as f:
                f.write(np.stack(decoded).tobytes())
        else:
            assert all((a == stored(k, 64, 64)).all() for k, a in enumerate(decoded)), name


def rgb_folder():
    """Two RGB slices (8 bits, interleaved): R = stored % 256, G = (2 stored) % 256, B = 255 - R."""
    d = fresh("rgb")
    for k in range(2):
        ds = slice_at("rgb", 15, "Colour", k, (0.0, 0.0, 2.0 * k))
        del ds.RescaleSlope
        del ds.RescaleIntercept
        v = stored(k)
        rgb = np.stack([v % 256, (2 * v) % 256, 255 - v % 256], axis=-1).astype("u1")
        ds.Rows, ds.Columns = v.shape
        ds.SamplesPerPixel = 3
        ds.PlanarConfiguration = 0
        ds.PhotometricInterpretation = "RGB"
        ds.BitsAllocated = ds.BitsStored = 8
        ds.HighBit = 7
        ds.PixelRepresentation = 0
        ds.PixelData = rgb.tobytes()
        save(ds, os.path.join(d, f"c{k}.dcm"))


def derived_folder():
    """A series of derived images only (a reformat): kept, unlike derived images mixed into a
    series of original ones."""
    d = fresh("derived")
    for k in range(3):
        ds = slice_at("derived", 16, "MPR", k, (0.0, 0.0, 1.0 * k))
        ds.ImageType = ["DERIVED", "SECONDARY", "MPR"]
        save(ds, os.path.join(d, f"d{k}.dcm"))


def hand_written(ds, path, meta_syntax, implicit, preamble=bytes(128)):
    """A file written piece by piece: `preamble`, DICM, a meta group naming `meta_syntax`, and
    the data set encoded implicit or explicit VR whatever the meta group says."""
    from pydicom.filebase import DicomBytesIO
    from pydicom.filewriter import write_dataset, write_file_meta_info

    ds.SOPInstanceUID = uid(path)
    body = DicomBytesIO()
    body.is_little_endian, body.is_implicit_VR = True, implicit
    write_dataset(body, ds)
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = ds.SOPClassUID
    meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
    meta.TransferSyntaxUID = meta_syntax
    head = DicomBytesIO()
    head.is_little_endian, head.is_implicit_VR = True, False
    write_file_meta_info(head, meta, enforce_standard=True)
    with open(path, "wb") as f:
        f.write(preamble + b"DICM" + head.getvalue() + body.getvalue())


def odd_files():
    """A data set in implicit VR under a meta group saying explicit (as some writers do), and a
    file whose preamble is a TIFF header (dual-personality files)."""
    ds = slice_at("mismatch", 17, "Mismatch", 0, (0.0, 0.0, 0.0))
    hand_written(ds, os.path.join(OUT, "mismatch.dcm"), ExplicitVRLittleEndian, implicit=True)
    ds = slice_at("tiffpre", 18, "TIFF preamble", 0, (0.0, 0.0, 0.0))
    preamble = (b"II*\x00" + (600000).to_bytes(4, "little")).ljust(128, b"\x00")
    hand_written(ds, os.path.join(OUT, "tiffpreamble.dcm"), ExplicitVRLittleEndian,
                 implicit=False, preamble=preamble)


def jpeg_lossless_folder():
    """Series 14 compressed by dcmcjpeg to JPEG lossless, first-order prediction (SV1)."""
    d = fresh("jpegll")
    if shutil.which("dcmcjpeg") is None:
        sys.exit("dcmcjpeg (Debian package dcmtk) is needed for the JPEG lossless series")
    tmp = os.path.join(OUT, "jpegll-native")
    shutil.rmtree(tmp, ignore_errors=True)
    for k in range(4):
        ds = slice_at("jpegll", 14, "Lossless", k, (0.0, 0.0, 2.0 * k))
        src = os.path.join(tmp, f"j{k}.dcm")
        save(ds, src)
        os.makedirs(d, exist_ok=True)
        subprocess.run(["dcmcjpeg", "+e1", "+un", src, os.path.join(d, f"j{k}.dcm")],
                       check=True)
    shutil.rmtree(tmp)


if __name__ == "__main__":
    # Every fixture, or only those named: python3 make_dicom.py j2k_folders
    ALL = [ct_folder, gap_folder, tilt_folder, mono1_folder, rescale_folder, fourd_folder,
           enhanced_file, deflated_file, no_preamble_file, unsupported_file, rgb_folder,
           derived_folder, odd_files, jpeg_lossless_folder, j2k_folders, jxl_folders]
    names = sys.argv[1:]
    for make in ALL:
        if not names or make.__name__ in names:
            make()
    print("fixtures written to", OUT)
