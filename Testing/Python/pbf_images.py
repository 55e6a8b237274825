"""What the rendering tests (pbf_gui.py and pbf_gui_apply.py in the GUI, pbf_show.py and
pbf_view_time.py in pvbatch) read from a view: a screenshot as pixels, the hues it shows, and
whether a box is wholly in view."""
import colorsys

import numpy
from vtkmodules.util import numpy_support
from vtkmodules.vtkIOImage import vtkPNGReader


def read_png(path):
    """The RGB pixels of a PNG as an int array (height, width, 3)."""
    reader = vtkPNGReader()
    reader.SetFileName(path)
    reader.Update()
    image = reader.GetOutput()
    width, height, _ = image.GetDimensions()
    pixels = numpy_support.vtk_to_numpy(image.GetPointData().GetScalars())
    return pixels.reshape(height, width, -1)[:, :, :3].astype(int)


def source_pixels(view, source, path, resolution=None):
    """A screenshot of view saved at path (at resolution, default the view's size) and the mask of
    its pixels that change when source is hidden: the source's own pixels, whatever the
    background and the other displays draw. The source is shown again afterwards."""
    from paraview import simple

    def shot(where):
        if resolution:
            simple.SaveScreenshot(where, view, ImageResolution=resolution)
        else:
            simple.SaveScreenshot(where, view)
        return read_png(where)

    with_source = shot(path)
    simple.Hide(source, view)
    without = shot(path[:-len(".png")] + "_empty.png")
    simple.Show(source, view)
    simple.Render(view)
    return with_source, numpy.any(with_source != without, axis=2)


def corners_off_view(view, bounds):
    """The corners of bounds (x0, x1, y0, y1, z0, z1) that project outside the view, with where
    they land: [] when the whole box is in view."""
    renderer = view.GetRenderer()
    width, height = view.ViewSize
    (x0, x1, y0, y1, z0, z1) = bounds
    off = []
    for corner in [(x, y, z) for x in (x0, x1) for y in (y0, y1) for z in (z0, z1)]:
        renderer.SetWorldPoint(corner[0], corner[1], corner[2], 1.0)
        renderer.WorldToDisplay()
        px, py, _ = renderer.GetDisplayPoint()
        if not (0 <= px <= width and 0 <= py <= height):
            off.append((corner, (round(px), round(py))))
    return off


def hues(pixels, share=0.01):
    """The 15-degree hue bins (their lower edges in degrees) that hold at least `share` of the
    given pixels' saturated ones (saturation and value >= 0.2: the color map's colors, not the
    gray shading and white of a lit sphere's rim). Cool to Warm, ParaView's default map, runs
    through four such bins: blue 232, light blue 221, (gray), salmon 19, red 348 degrees."""
    bins = numpy.zeros(24, dtype=int)
    for r, g, b in numpy.asarray(pixels).reshape(-1, 3) / 255.0:
        h, s, v = colorsys.rgb_to_hsv(r, g, b)
        if s >= 0.2 and v >= 0.2:
            bins[int(h * 24) % 24] += 1
    return [15 * i for i in range(24) if bins[i] > 0 and bins[i] >= share * bins.sum()]
