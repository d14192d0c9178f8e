"""measure_frame and Tracker on arrays: widths against the renderer's exact truth, every array
layout the library reads in place, and the ValueErrors for the rest."""

import numpy as np
import pytest

import clogscope


@pytest.fixture(scope="module")
def reference():
    """A rendered 720p reference frame (400 µm strand at 3 µm/px, blur 1.5, noise 3)."""
    images, truth = clogscope.render(clogscope.SceneParams(seed=11))
    return images[0], truth.iloc[0]


def test_width_matches_the_rendered_truth(reference):
    image, truth = reference
    m = clogscope.measure_frame(image)
    assert m.valid and bool(m) and m.status == clogscope.FrameStatus.valid and m.reason == ""
    assert abs(m.width_px - truth["width_px"]) < 0.1  # the README's accuracy: ≤ 0.1 px
    assert 0 < m.width_sigma_px < 0.1
    assert abs(m.tip_x_px - truth["tip_x_px"]) < 1 and abs(m.tip_y_px - truth["tip_y_px"]) < 1
    # The nozzle's face shows on both sides here: the tip is fixed to a fraction of a px, and
    # within 3 of its σ of the rendered one.
    assert 0 < m.tip_sigma_px < 1
    assert abs(m.tip_y_px - truth["tip_y_px"]) < 3 * m.tip_sigma_px
    assert m.polarity == clogscope.Polarity.bright
    assert len(m.calipers) == m.calipers_total >= m.calipers_used > 0
    assert "width_px=" in repr(m)
    # The σ in its parts, largest first: the root of the sum of their squares makes it up.
    parts = m.sigma_parts
    assert [s for _, s in parts] == sorted((s for _, s in parts), reverse=True)
    assert abs(np.hypot.reduce([s for _, s in parts]) - m.width_sigma_px) < 1e-9


@pytest.mark.parametrize("kind", ["uint16", "colour", "silhouette"])
def test_other_frames_match_their_truth(kind):
    scene = clogscope.SceneParams(seed=12, tilt_deg=-6)
    if kind == "uint16":
        scene.bit_depth = 16
    elif kind == "colour":
        scene.colour = True
    else:
        scene.set_silhouette()
    images, truth = clogscope.render(scene)
    expected_dtype = np.uint16 if kind == "uint16" else np.uint8
    assert images.dtype == expected_dtype
    assert images.shape[1:3] == (720, 1280)
    m = clogscope.measure_frame(images[0])
    assert m.valid, m
    assert abs(m.width_px - truth["width_px"][0]) < 0.1
    assert abs(m.angle_deg - truth["angle_deg"][0]) < 0.5
    if kind == "silhouette":
        assert m.polarity == clogscope.Polarity.dark


def test_a_crop_is_read_in_place_and_measured_as_its_copy(reference):
    image, truth = reference
    big = np.zeros((800, 1400), np.uint8)
    big[40:760, 60:1340] = image
    crop = big[40:760, 60:1340]  # rows at a stride of 1400 bytes: no copy
    assert not crop.flags["C_CONTIGUOUS"]
    a = clogscope.measure_frame(crop)
    b = clogscope.measure_frame(np.ascontiguousarray(crop))
    assert a.valid and (a.width_px, a.width_sigma_px, a.tip_x_px) == (
        b.width_px, b.width_sigma_px, b.tip_x_px)
    # A read-only array is read as it is.
    ro = image.copy()
    ro.setflags(write=False)
    assert clogscope.measure_frame(ro).width_px == b.width_px


def test_an_empty_scene_gives_a_reason_not_an_error():
    scene = clogscope.SceneParams(strand=False, seed=3)
    images, _ = clogscope.render(scene)
    m = clogscope.measure_frame(images[0])
    assert not m.valid
    assert m.status == clogscope.Reason.no_strand and m.reason == "no_strand"
    assert m.detail


def test_status_names_are_the_reason_column_names():
    names = set(clogscope.FrameStatus.__members__)
    assert {"valid", "no_strand", "no_tip", "occluded", "imprecise", "width_outlier",
            "band_outside_frame", "unreadable"} <= names


@pytest.mark.parametrize("array, message", [
    (np.zeros((100, 100), np.float32), "frame: dtype float32 is not supported"),
    (np.zeros((100, 100), np.int16), "frame: dtype int16 is not supported"),
    (np.zeros((100, 100, 2), np.uint8), "frame: 2 channels"),
    (np.zeros((4, 100, 100, 3), np.uint8), "frame: 4 dimensions"),
    (np.zeros((100,), np.uint8), "frame: 1 dimensions"),
    (np.zeros((0, 100), np.uint8), "frame: empty array"),
    (np.zeros((100, 200), np.uint8)[:, ::2], "frame: the pixels of a row are not adjacent"),
    (np.zeros((100, 100), np.uint8)[::-1], "frame: row stride -100 bytes"),
    (np.zeros((3, 100, 100), np.uint8).transpose(1, 2, 0), "frame: the channels of a pixel"),
    (np.zeros((100, 100), ">u2"), "frame: big-endian uint16"),
])
def test_arrays_it_cannot_read_raise_value_error(array, message):
    with pytest.raises(ValueError) as e:
        clogscope.measure_frame(array)
    assert str(e.value).startswith(message), str(e.value)


def test_bad_options_raise_value_error_with_the_librarys_message(reference):
    image, _ = reference
    options = clogscope.MeasureOptions(band_height_px=2)
    with pytest.raises(ValueError, match=r"^measure options: band height must be at least 4 px$"):
        options.validate()
    with pytest.raises(ValueError, match=r"^measure options: band height must be at least 4 px$"):
        clogscope.measure_frame(image, options)
    with pytest.raises(ValueError, match=r"^measure options: band height must be at least 4 px$"):
        clogscope.Tracker(options)
    with pytest.raises(ValueError, match=r"lies outside the 1280x720 frame"):
        clogscope.measure_frame(image, clogscope.MeasureOptions(roi=(1200, 600, 200, 200)))
    with pytest.raises(TypeError, match="unknown keyword argument 'band_start_um'"):
        clogscope.MeasureOptions(band_start_um=50)


def test_options_change_the_measurement(reference):
    image, truth = reference
    roi = (440, 100, 400, 500)
    options = clogscope.MeasureOptions(roi=roi, caliper_spacing_px=8)
    assert options.roi == roi and options.caliper_spacing_px == 8
    m = clogscope.measure_frame(image, options)
    assert m.valid and abs(m.width_px - truth["width_px"]) < 0.1
    default = clogscope.measure_frame(image)
    assert m.calipers_total < default.calipers_total  # 8-px calipers: half as many
    # A polarity the frame does not have finds no strand.
    dark = clogscope.measure_frame(image, clogscope.MeasureOptions(polarity=clogscope.Polarity.dark))
    assert not dark.valid


def test_tracker_follows_a_video_and_matches_the_truth():
    scene = clogscope.SceneParams(width_jitter_um=2, seed=21)
    images, truth = clogscope.render(scene, frames=8)
    tracker = clogscope.Tracker()
    widths = [tracker.measure(f) for f in images]
    assert all(m.valid for m in widths)
    errors = np.array([m.width_px for m in widths]) - truth["width_px"].to_numpy()
    assert np.max(np.abs(errors)) < 0.1
    # The jitter is seen: measured widths follow the rendered ones frame by frame.
    assert np.corrcoef([m.width_px for m in widths], truth["width_px"])[0, 1] > 0.9
    assert tracker.full_detections == 1 and tracker.tracked_frames == 7
    tracker.reset()
    tracker.measure(images[0])
    assert tracker.full_detections == 2


def test_a_strand_clipped_at_limited_range_white_is_saturated():
    """A strand at the camera's white, half its pixels clipped by the noise, then put into
    limited-range luma as a video stores it (16-235): the clip sits at 235, not 255. Measured in that range, by
    measure_frame, by a Tracker whose options say so and by one told per frame, it is
    `saturated`: never a width from a strand whose plateau is cut off."""
    images, _ = clogscope.render(clogscope.SceneParams(seed=13, strand_level=255, noise_sigma=1.5))
    rendered = images[0]
    assert (rendered == 255).mean() > 0.02  # the renderer clipped the strand at 255
    luma = np.rint(16 + rendered.astype(np.float64) * 219 / 255).astype(np.uint8)
    limited = clogscope.MeasureOptions(luma_range=clogscope.LumaRange.limited)
    for m in (clogscope.measure_frame(luma, limited),
              clogscope.Tracker(limited).measure(luma),
              clogscope.Tracker().measure(luma, luma_range=clogscope.LumaRange.limited)):
        assert m.status == clogscope.FrameStatus.saturated, (m.status, m.width_px)
    # The same pixels at full scale: clipped at 255, where full range looks.
    assert clogscope.measure_frame(rendered).status == clogscope.FrameStatus.saturated
