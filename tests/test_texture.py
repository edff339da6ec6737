"""infuse.texture and infuse.mesh.area_normals: the sampling and normals every mesh reader shares."""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from infuse.mesh import area_normals
from infuse.texture import bilinear, decode_image, srgb_to_linear


def test_bilinear_reads_pixel_centres_and_blends_between_them():
    pixels = np.arange(2 * 3 * 4, dtype=np.float64).reshape(2, 3, 4)  # 2 rows, 3 columns
    centres_u = (np.arange(3) + 0.5) / 3
    assert np.allclose(bilinear(pixels, centres_u, np.full(3, 0.25)), pixels[0])
    assert np.allclose(bilinear(pixels, centres_u, np.full(3, 0.75)), pixels[1])
    middle = bilinear(pixels, np.array([1.0 / 3]), np.array([0.5]))[0]  # between columns 0, 1 and rows 0, 1
    assert np.allclose(middle, pixels[:, :2].mean(axis=(0, 1)))


def test_edges_hold_or_wrap():
    pixels = np.zeros((1, 2, 4))
    pixels[0, 1] = 1.0
    left_edge = np.array([0.0]), np.array([0.5])
    assert np.allclose(bilinear(pixels, *left_edge), 0.0)  # held: the edge pixel
    assert np.allclose(bilinear(pixels, *left_edge, wrap_edges=True), 0.5)  # halfway to the opposite edge


def test_images_decode_to_linear_rgba_reduced(tmp_path):
    path = tmp_path / "grey.png"
    Image.new("RGB", (600, 300), (188, 188, 188)).save(path)
    pixels = decode_image(path, size=64)
    assert pixels.shape == (32, 64, 4)
    assert np.allclose(pixels[..., :3], srgb_to_linear(188 / 255)) and np.allclose(pixels[..., 3], 1.0)
    assert np.allclose(decode_image(path.read_bytes(), size=64), pixels)
    assert srgb_to_linear(188 / 255) == pytest.approx(0.5, abs=0.01)


def test_area_normals_sum_the_faces_around_each_point():
    # a unit square in the XZ plane (two triangles, counter-clockwise from +Y) and a lone point
    positions = np.array([[0, 0, 0], [0, 0, 1], [1, 0, 1], [1, 0, 0], [5, 5, 5]], dtype=float)
    triangles = np.array([[0, 1, 2], [0, 2, 3]])
    normals = area_normals(positions, triangles)
    assert np.allclose(normals[[0, 2]], [[0, 2, 0]] * 2)  # two faces of area 1/2 each, times 2
    assert np.allclose(normals[[1, 3]], [[0, 1, 0]] * 2)
    assert np.allclose(normals[4], 0.0)
