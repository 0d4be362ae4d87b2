"""Image writers: bit-exact EXR round trips read by OpenEXR itself, PNG via Pillow, atomicity."""

import os

import numpy as np
import OpenEXR
import pytest
from failing_exr import FailingExrFile
from PIL import Image

from skyscatter.errors import InputError
from skyscatter.render import image_io
from skyscatter.render.image_io import read_exr, read_exr_attributes, write_exr, write_png


@pytest.fixture
def hdr_image():
    rng = np.random.default_rng(7)
    image = (rng.lognormal(mean=0.0, sigma=6.0, size=(17, 23, 3))).astype(np.float32)
    image[0, 0] = [0.0, np.finfo(np.float32).tiny, np.finfo(np.float32).max]
    return image


def test_exr_round_trip_is_bit_exact_with_rgb_names(tmp_path, hdr_image):
    path = write_exr(tmp_path / "sky.exr", hdr_image)
    image, names = read_exr(path)
    assert names == ("R", "G", "B")
    assert image.dtype == np.float32 and image.shape == hdr_image.shape
    np.testing.assert_array_equal(image.view(np.uint32), hdr_image.view(np.uint32))


def test_exr_is_a_standard_zip_file_with_separate_rgb_channels(tmp_path, hdr_image):
    # Read with the OpenEXR library directly, as another tool would.
    write_exr(tmp_path / "sky.exr", hdr_image)
    exr = OpenEXR.File(str(tmp_path / "sky.exr"), separate_channels=True)
    assert set(exr.channels()) == {"R", "G", "B"}
    assert exr.header()["compression"] == OpenEXR.ZIP_COMPRESSION
    np.testing.assert_array_equal(exr.channels()["G"].pixels, hdr_image[..., 1])


@pytest.mark.parametrize("names", [("Y",), ("X", "Y", "Z"), ("R", "G", "B", "A")])
def test_exr_channel_names_are_preserved(tmp_path, names):
    image = np.arange(4 * 5 * len(names), dtype=np.float32).reshape(4, 5, len(names))
    write_exr(tmp_path / "c.exr", image, channel_names=names)
    back, back_names = read_exr(tmp_path / "c.exr")
    assert back_names == names
    np.testing.assert_array_equal(back, image)


def test_exr_half_input_stays_half_and_reads_back_exactly(tmp_path):
    image = np.array([[[0.5, 1.0, 65504.0]]], dtype=np.float16)
    write_exr(tmp_path / "h.exr", image)
    exr = OpenEXR.File(str(tmp_path / "h.exr"), separate_channels=True)
    assert exr.channels()["R"].pixels.dtype == np.float16
    np.testing.assert_array_equal(read_exr(tmp_path / "h.exr")[0], image.astype(np.float32))


def test_exr_attributes_round_trip(tmp_path):
    attributes = {"units": "cd/m^2", "skyscatter_sun_zenith_deg": "85.0"}
    write_exr(tmp_path / "a.exr", np.zeros((2, 2, 1)), attributes=attributes)
    assert read_exr_attributes(tmp_path / "a.exr") == attributes


def test_writers_are_deterministic(tmp_path, hdr_image):
    for name in ("a", "b"):
        write_exr(tmp_path / f"{name}.exr", hdr_image, attributes={"units": "W/m^2/sr"})
        write_png(tmp_path / f"{name}.png", np.full((3, 4, 3), 9, dtype=np.uint8))
    assert (tmp_path / "a.exr").read_bytes() == (tmp_path / "b.exr").read_bytes()
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()


def test_png_round_trip_through_pillow(tmp_path):
    rgb8 = np.random.default_rng(3).integers(0, 256, size=(9, 13, 3), dtype=np.uint8)
    path = write_png(tmp_path / "x.png", rgb8, text={"Software": "skyscatter"})
    with Image.open(path) as picture:
        assert picture.mode == "RGB" and picture.text == {"Software": "skyscatter"}
        np.testing.assert_array_equal(np.asarray(picture), rgb8)


def test_writers_create_missing_directories_with_the_usual_file_mode(tmp_path):
    target = tmp_path / "a" / "b" / "sky.png"
    write_png(target, np.zeros((2, 2, 3), dtype=np.uint8))
    umask = os.umask(0)
    os.umask(umask)
    assert target.stat().st_mode & 0o777 == 0o666 & ~umask  # not mkstemp's 0600
    assert os.listdir(target.parent) == ["sky.png"]


def test_failed_exr_write_keeps_the_old_file_and_leaves_no_partial_file(tmp_path, hdr_image,
                                                                       monkeypatch):
    path = write_exr(tmp_path / "sky.exr", hdr_image)
    before = path.read_bytes()
    monkeypatch.setattr(image_io.OpenEXR, "File", FailingExrFile)
    with pytest.raises(InputError, match=r"cannot write .*sky\.exr: No space left on device"):
        write_exr(path, np.zeros((2, 2, 3)))
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["sky.exr"]


def test_failed_png_write_keeps_the_old_file_and_leaves_no_partial_file(tmp_path, monkeypatch):
    path = write_png(tmp_path / "sky.png", np.full((2, 2, 3), 200, dtype=np.uint8))
    before = path.read_bytes()

    def failing_save(self, fp, *args, **kwargs):
        with open(fp, "wb") as stream:
            stream.write(b"\x89PNG partial")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Image.Image, "save", failing_save)
    with pytest.raises(InputError, match=r"cannot write .*sky\.png: No space left on device"):
        write_png(path, np.zeros((2, 2, 3), dtype=np.uint8))
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["sky.png"]


def test_interrupted_write_cleans_up_and_reraises(tmp_path, monkeypatch):
    def interrupted_save(self, fp, *args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(Image.Image, "save", interrupted_save)
    with pytest.raises(KeyboardInterrupt):
        write_png(tmp_path / "sky.png", np.zeros((2, 2, 3), dtype=np.uint8))
    assert os.listdir(tmp_path) == []


def test_unwritable_path_names_the_path(tmp_path):
    blocker = tmp_path / "not_a_directory"
    blocker.write_text("")
    with pytest.raises(InputError, match=r"cannot write .*not_a_directory/sky\.exr: "):
        write_exr(blocker / "sky.exr", np.zeros((2, 2, 3)))
    with pytest.raises(InputError, match=r"cannot write .*not_a_directory/sky\.png: "):
        write_png(blocker / "sky.png", np.zeros((2, 2, 3), dtype=np.uint8))


def test_read_exr_of_missing_or_corrupt_file_names_the_path(tmp_path):
    with pytest.raises(InputError, match=r"cannot read .*missing\.exr: no such file"):
        read_exr(tmp_path / "missing.exr")
    (tmp_path / "junk.exr").write_bytes(b"not an exr")
    with pytest.raises(InputError, match=r"cannot read .*junk\.exr: not a readable OpenEXR"):
        read_exr(tmp_path / "junk.exr")


@pytest.mark.parametrize("call, match", [
    (lambda p: write_exr(p / "x.exr", np.zeros((4, 4))), r"shape \(height, width, channels\)"),
    (lambda p: write_exr(p / "x.exr", np.zeros((4, 4, 2))), "give channel_names"),
    (lambda p: write_exr(p / "x.exr", np.zeros((4, 4, 2)), ("R", "R")), "distinct"),
    (lambda p: write_exr(p / "x.exr", np.zeros((4, 4, 1)), attributes={"channels": "x"}),
     "standard header name"),
    (lambda p: write_png(p / "x.png", np.zeros((4, 4, 3))), "must be uint8"),
])
def test_bad_image_arguments_raise_input_error_and_write_nothing(tmp_path, call, match):
    with pytest.raises(InputError, match=match):
        call(tmp_path)
    assert os.listdir(tmp_path) == []
