"""What the rendering tests (pbf_gui.py in the GUI, pbf_show.py in pvbatch) read from a view: a
screenshot as pixels, and whether a box is wholly in view."""
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
