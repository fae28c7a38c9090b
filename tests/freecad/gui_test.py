# SPDX-License-Identifier: LGPL-2.1-or-later
"""GUI test in a real FreeCAD window (run by run.sh under Xvfb): select a mesh, run the command,
set values in the panel, Apply, OK; check the object and its report; take a screenshot."""

import os
import subprocess
import sys
import time
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path[:0] = [ROOT, HERE]
SHOT = os.environ.get("HEXMERGE_SCREENSHOT", "/tmp/hexmerge_gui.png")


def wait(pred, seconds=60):
    from PySide import QtGui
    end = time.time() + seconds
    while time.time() < end:
        QtGui.QApplication.processEvents()
        if pred():
            return True
        time.sleep(0.05)
    return False


def color_fractions(path):
    """Fractions of the 3D view's pixels (the screenshot's middle, away from the toolbars and
    the navigation cube) that are clearly red, green, FreeCAD's default mesh orange, or the pure
    green FreeCAD 0.20 gives a face whose element has no colour."""
    from PySide import QtGui
    image = QtGui.QImage(path)
    w, h = image.width(), image.height()
    counts = {"red": 0, "green": 0, "orange": 0, "uncoloured": 0}
    total = 0
    for y in range(int(0.2 * h), int(0.65 * h), 3):
        for x in range(int(0.3 * w), int(0.85 * w), 3):
            c = QtGui.QColor(image.pixel(x, y))
            r, g, b = c.red(), c.green(), c.blue()
            total += 1
            if g > 2.8 * max(r, b, 1) and g > 60:
                counts["uncoloured"] += 1
            elif r > 1.6 * g and r > 1.6 * b and r > 60:
                counts["red"] += 1
            elif g > 1.4 * r and g > 1.4 * b and g > 60:
                counts["green"] += 1
            elif r > 150 and 0.55 * r < g < 0.85 * r and b < 0.3 * r:
                counts["orange"] += 1
    return {k: v / total for k, v in counts.items()}


def check_colors(path, report):
    """Colour by type shows: pyramids red and prisms green where the mesh has them, and no
    face left in FreeCAD's default orange."""
    counts = report["output_counts"]
    shares = color_fractions(path)
    print("colour shares in the view: {}".format(shares))
    if counts.get("pyramid", 0):
        assert shares["red"] > 0.005, "no red (pyramid) faces in the view: {}".format(shares)
    if counts.get("wedge", 0):
        assert shares["green"] > 0.005, "no green (prism) faces in the view: {}".format(shares)
    assert shares["orange"] < 0.002, "faces in the default colour: {}".format(shares)
    assert shares["uncoloured"] < 0.002, "faces of elements without colour: {}".format(shares)


def main():
    import FreeCAD
    import FreeCADGui
    from PySide import QtGui
    import helpers
    from freecad.hexmerge import commands, mesh_hexdominant
    from freecad.hexmerge.task_mesh_hexdominant import TaskPanelHexDominant

    FreeCADGui.activateWorkbench("FemWorkbench")
    doc, mesh = helpers.box_doc("1st", 8.0, name="HexMergeGui")
    doc.getObject("Box").ViewObject.Visibility = False
    cmd = FreeCADGui.Command.get("HexMerge_MeshHexDominant")
    assert cmd is not None, "command not registered"

    # bad case: nothing selected -> inactive, and Activated changes nothing
    FreeCADGui.Selection.clearSelection()
    assert commands.selected_tet_mesh()[0] is None
    assert not commands.HexDominantFromTetrahedra().IsActive(), "active without selection"
    n = len(doc.Objects)
    commands.HexDominantFromTetrahedra().Activated()
    assert len(doc.Objects) == n

    FreeCADGui.Selection.addSelection(mesh)
    assert commands.HexDominantFromTetrahedra().IsActive(), "inactive with a tet mesh selected"
    FreeCADGui.runCommand("HexMerge_MeshHexDominant")
    assert wait(lambda: getattr(TaskPanelHexDominant, "current", None) is not None, 10)
    panel = TaskPanelHexDominant.current
    obj = panel.obj
    assert panel.gb_shape.isHidden(), "shape options shown for a tet mesh source"
    panel.widgets["MinScaledJacobian"][1].setValue(0.35)
    panel.widgets["MakePyramids"][1].setChecked(True)
    panel.form.ckb_pyramids_as_hexahedra.setChecked(True)
    panel.apply()
    assert wait(lambda: panel.run is not None and not panel.run.running()
                and panel.form.pb_apply.isEnabled(), 60), "apply did not finish"
    assert obj.Report, "no report after Apply: " + panel.form.l_status.text()
    assert panel.form.tw_results.rowCount() > 5
    FreeCADGui.ActiveDocument.activeView().viewIsometric()
    FreeCADGui.SendMsgToActiveView("ViewFit")
    wait(lambda: False, 1.5)
    subprocess.run(["import", "-window", "root", SHOT], check=True)
    check_colors(SHOT, mesh_hexdominant.report_dict(obj))
    assert panel.form.tw_results.item(1, 0).icon() is not None
    panel.accept()
    wait(lambda: False, 0.5)

    assert doc.getObject(obj.Name) is not None, "OK did not keep the object"
    assert abs(obj.MinScaledJacobian - 0.35) < 1e-9
    report = mesh_hexdominant.report_dict(obj)
    assert report["output_cells"] == obj.FemMesh.VolumeCount > 0
    assert report["input_tets"] == mesh.FemMesh.VolumeCount
    assert obj.ViewObject.ColorByType  # ElementColor is write-only in FreeCAD 0.20

    # Cancel undoes: a second object, cancelled
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(mesh)
    names = {o.Name for o in doc.Objects}
    FreeCADGui.runCommand("HexMerge_MeshHexDominant")
    assert wait(lambda: TaskPanelHexDominant.current is not panel, 10)
    TaskPanelHexDominant.current.reject()
    wait(lambda: False, 0.5)
    assert {o.Name for o in doc.Objects} == names, "Cancel left objects behind"

    # Shape mode: the box itself, meshed at a target size set in the panel
    box = doc.getObject("Box")
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(box)
    assert commands.HexDominantFromShape().IsActive(), "inactive with a solid selected"
    assert not commands.HexDominantFromTetrahedra().IsActive()
    previous = TaskPanelHexDominant.current
    FreeCADGui.runCommand("HexMerge_MeshHexDominantFromShape")
    assert wait(lambda: TaskPanelHexDominant.current is not previous, 10)
    panel = TaskPanelHexDominant.current
    shape_obj = panel.obj
    assert not panel.gb_shape.isHidden(), "no shape options for a shape source"
    assert "TargetSize" in panel.widgets and "BoundaryLayers" in panel.widgets
    panel.widgets["TargetSize"][1].setProperty("rawValue", 10.0)
    panel.widgets["SecondOrder"][1].setChecked(False)
    panel.apply()
    assert wait(lambda: panel.run is not None and not panel.run.running()
                and panel.form.pb_apply.isEnabled(), 60), "apply (shape) did not finish"
    shape_report = mesh_hexdominant.report_dict(shape_obj)
    assert shape_report.get("meshing"), "no meshing report: " + panel.form.l_status.text()
    rows = [panel.form.tw_results.item(i, 0).text() for i in range(panel.form.tw_results.rowCount())]
    assert "target size" in rows, rows
    panel.accept()
    wait(lambda: False, 0.5)
    assert abs(shape_obj.TargetSize.Value - 10.0) < 1e-9 and not shape_obj.SecondOrder
    assert shape_report["output_counts"]["hex"] == 72, shape_report["output_counts"]

    std = subprocess.run(["convert", SHOT, "-format", "%[fx:standard_deviation]", "info:"],
                         capture_output=True, text=True, check=True).stdout
    assert float(std) > 0.02, "screenshot looks blank (std {})".format(std)
    print("GUI TEST PASSED: {} -> {}; shape: {}; screenshot {}".format(
        mesh.FemMesh.VolumeCount, obj.Summary, shape_obj.Summary, SHOT))


try:
    main()
except Exception:
    traceback.print_exc()
    print("GUI TEST FAILED")
sys.stdout.flush()
os._exit(0)
