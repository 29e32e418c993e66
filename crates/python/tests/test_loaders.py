"""`volgraph.load` of the files users bring — NIfTI written by nibabel, a DICOM series written by
pydicom — reads what the command line reads: the same voxels, spacing and patient frame, and
the same image bit for bit (issue 46). `Volume.array` is a read-only view, not a copy."""

from pathlib import Path

import numpy as np
import pytest
from helpers import ball_nifti, cli, ramp_volume, read_png

import volgraph


def same_render_as_the_cli(volume, path, tmp_path):
    png = tmp_path / "cli.png"
    cli("render", "basic/fragment_raycast", "--volume", path, "--size", "48x40", "-o", png, cwd=tmp_path)
    ours = volgraph.render("basic/fragment_raycast", volume, size=(48, 40))
    return np.array_equal(ours[..., :3], read_png(png)[..., :3])


def test_a_loaded_volumes_array_is_a_read_only_view_of_its_voxels(tmp_path):
    a = ramp_volume()
    raw = tmp_path / "ball_24x20x16_uint16.raw"
    a.tofile(raw)
    v = volgraph.load(raw)
    first, second = v.array, v.array
    assert first is second, "the same array each time, not a copy"
    assert not first.flags.writeable and not first.flags.owndata, "a view of the loader's buffer"
    with pytest.raises(ValueError):
        first[0, 0, 0] = 1
    assert np.array_equal(first, a)
    changed = first.copy()
    changed[:8] = 0
    assert not np.array_equal(volgraph.render("basic/fragment_raycast", changed, size=(32, 32)),
                              volgraph.render("basic/fragment_raycast", v, size=(32, 32)))
    assert np.array_equal(v.world_from_volume, np.diag([1.0, 1.0, 1.0, 1.0]))


def test_nifti_from_nibabel_reads_as_the_cli_reads_it(tmp_path):
    path = tmp_path / "ball.nii.gz"
    data = ball_nifti(path)  # nibabel's [x, y, z]
    v = volgraph.load(path)
    assert v.dims == (24, 20, 16) and v.spacing == pytest.approx((0.8, 0.9, 1.5))
    assert v.meta["frame"].startswith("LPS")
    # RAS (NIfTI) to LPS (DICOM, what volgraph shows): x and y reversed, as ITK reads it.
    assert np.array_equal(v.array, data.transpose(2, 1, 0)[:, ::-1, ::-1])
    # Voxel (0, 0, 0) of the array is the file's (23, 19, 0): at RAS (-10 + 23·0.8, 20 + 19·0.9, 5).
    corner = v.world_from_volume @ np.array([0, 0, 0, 1.0])
    assert corner[:3] == pytest.approx((10.0 - 23 * 0.8, -20.0 - 19 * 0.9, 5.0))
    assert same_render_as_the_cli(v, path, tmp_path)


def test_a_dicom_series_from_pydicom_reads_as_the_cli_reads_it(tmp_path):
    from pydicom.dataset import Dataset, FileMetaDataset
    from pydicom.uid import CTImageStorage, ExplicitVRLittleEndian, generate_uid

    hu = (ramp_volume().astype(np.int32) // 40 - 1024).astype(np.int16)  # [z, y, x], -1024..476 HU
    series, study, frame = generate_uid(), generate_uid(), generate_uid()
    folder = tmp_path / "ct"
    folder.mkdir()
    for z in range(hu.shape[0]):
        meta = FileMetaDataset()
        meta.MediaStorageSOPClassUID = CTImageStorage
        meta.MediaStorageSOPInstanceUID = generate_uid()
        meta.TransferSyntaxUID = ExplicitVRLittleEndian
        ds = Dataset()
        ds.file_meta = meta
        ds.SOPClassUID, ds.SOPInstanceUID = CTImageStorage, meta.MediaStorageSOPInstanceUID
        ds.StudyInstanceUID, ds.SeriesInstanceUID, ds.FrameOfReferenceUID = study, series, frame
        ds.Modality, ds.PatientName, ds.SeriesDescription = "CT", "Test^Ball", "ball"
        ds.Rows, ds.Columns = hu.shape[1], hu.shape[2]
        ds.PixelSpacing = [0.7, 0.6]  # row spacing (y), column spacing (x)
        ds.SliceThickness = 2.0
        ds.ImagePositionPatient = [-8.0, -6.0, 30.0 + 2.0 * z]
        ds.ImageOrientationPatient = [1, 0, 0, 0, 1, 0]
        ds.InstanceNumber = z + 1
        ds.SamplesPerPixel, ds.PhotometricInterpretation = 1, "MONOCHROME2"
        ds.BitsAllocated, ds.BitsStored, ds.HighBit, ds.PixelRepresentation = 16, 16, 15, 1
        ds.RescaleIntercept, ds.RescaleSlope = 0, 1
        ds.PixelData = hu[z].tobytes()
        ds.save_as(folder / f"slice{z:03}.dcm", enforce_file_format=True)
    v = volgraph.load(folder)
    assert v.dims == (24, 20, 16) and v.spacing == pytest.approx((0.6, 0.7, 2.0))
    assert v.meta["modality"] == "CT" and v.meta["units"] == "HU" and v.meta["frame_of_reference"] == frame
    assert np.array_equal(v.array, hu)
    assert (v.world_from_volume @ np.array([0, 0, 0, 1.0]))[:3] == pytest.approx((-8.0, -6.0, 30.0))
    assert same_render_as_the_cli(v, folder, tmp_path)
