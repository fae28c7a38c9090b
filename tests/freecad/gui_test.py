# SPDX-License-Identifier: LGPL-2.1-or-later
"""GUI test in a real FreeCAD window (run by run.sh under Xvfb): FEM's Mesh menu entries; the
panel at the combo view's default width (no value cut off) and its wheel guard; Apply and OK on
a tet mesh and a shape; colours of first- and second-order meshes checked triangle by triangle;
Cancel during the engine (three times) leaves no timer and no error, and closing a panel lets go of
its form and quantity boxes without deleting through PySide (flag_as_qapp); OK without Apply runs
in the background; save and reopen print no error. Takes screenshots of the panel and of a coloured Hexa20 mesh."""

import os
import subprocess
import sys
import time
import traceback

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path[:0] = [ROOT, HERE, os.path.join(ROOT, "src", "python")]  # this checkout's engine first
SHOT = os.environ.get("HEXMERGE_SCREENSHOT", "/tmp/hexmerge_gui.png")
SHOT_COLORS = os.environ.get("HEXMERGE_SCREENSHOT_COLORS", "/tmp/hexmerge_colors.png")
COMBO_VIEW_WIDTH = 264  # FreeCAD 0.20's default combo view


def wait(pred, seconds=60):
    from PySide import QtGui
    end = time.time() + seconds
    while time.time() < end:
        QtGui.QApplication.processEvents()
        if pred():
            return True
        time.sleep(0.05)
    return False


def report_view_errors():
    """Lines of the Report view that are errors or tracebacks."""
    import FreeCADGui
    from PySide import QtGui
    dock = FreeCADGui.getMainWindow().findChild(QtGui.QDockWidget, "Report view")
    text = dock.findChild(QtGui.QTextEdit).toPlainText()
    return [l for l in text.splitlines()
            if "Traceback" in l or "Error" in l or "failed" in l or "setAttr" in l]


def expected_colors(vobj):
    """The colour of every drawn triangle by an independent route: its three corners are matched
    to mesh nodes by coordinates, the element holding all three is found, its type looked up."""
    from pivy import coin
    from freecad.hexmerge import colors, view_mesh_hexdominant as vp
    femmesh = vobj.Object.FemMesh
    material, binding, face_set = vp.scene_nodes(vobj)
    search = coin.SoSearchAction()
    search.setType(coin.SoCoordinate3.getClassTypeId())
    search.setInterest(coin.SoSearchAction.FIRST)
    search.setSearchingAll(True)
    search.apply(vobj.RootNode)
    group_coords = search.getPath().getTail().point.getValues()
    import numpy as np
    ids = list(femmesh.Nodes.keys())
    points = np.array([[p.x, p.y, p.z] for p in femmesh.Nodes.values()])
    drawn_points = np.array([[v[0], v[1], v[2]] for v in group_coords])
    nearest = [ids[int(np.argmin(((points - q) ** 2).sum(axis=1)))] for q in drawn_points]
    elements_of = {}
    for e in femmesh.Volumes:
        for n in femmesh.getElementNodes(e):
            elements_of.setdefault(n, set()).add(e)
    index = face_set.coordIndex.getValues()
    tri, out = [], []
    for i in index:
        if i >= 0:
            tri.append(i)
            continue
        nodes = [nearest[k] for k in tri]
        owners = set.intersection(*(elements_of[n] for n in nodes))
        assert owners, "triangle {} in no element".format(nodes)
        # A quad against two triangles (a non-conforming face) is drawn from both sides, and a
        # triangle of the quad has the corners of a triangle of the other side: either colour.
        out.append({colors.TYPE_COLORS[colors.element_kind(femmesh.getElementNodes(e))]
                    for e in owners})
        tri = []
    drawn = [tuple(c.getValue()) for c in material.diffuseColor.getValues()]
    return out, drawn, binding.value.getValue()


def check_colors(vobj, label):
    """Every drawn triangle has its element's type colour (to 1e-3)."""
    from pivy import coin
    expected, drawn, binding = expected_colors(vobj)
    assert binding == coin.SoMaterialBinding.PER_FACE, "{}: colours not per face".format(label)
    assert len(drawn) == len(expected), "{}: {} colours for {} triangles".format(
        label, len(drawn), len(expected))
    wrong = sum(1 for allowed, b in zip(expected, drawn)
                if min(max(abs(x - y) for x, y in zip(a, b)) for a in allowed) > 1e-3)
    assert wrong == 0, "{}: {} of {} triangles in a wrong colour".format(label, wrong, len(drawn))
    print("colours {}: {} triangles, all right".format(label, len(drawn)))


def check_fem_menu():
    import FreeCADGui
    from PySide import QtGui
    FreeCADGui.activateWorkbench("FemWorkbench")
    wait(lambda: False, 0.5)
    window = FreeCADGui.getMainWindow()
    names = ("Hex-dominant mesh from shape", "Hex-dominant mesh from tetrahedra")
    for kind, containers in (("menu", window.menuBar().findChildren(QtGui.QMenu)),
                             ("toolbar", window.findChildren(QtGui.QToolBar))):
        holder = [c for c in containers if any("Gmsh" in a.text() for a in c.actions())]
        assert holder, "no FEM {} with Gmsh".format(kind)
        texts = [a.text() for a in holder[0].actions()]
        gmsh = [i for i, t in enumerate(texts) if "Gmsh" in t][0]
        assert texts[gmsh + 1:gmsh + 3] == list(names), "FEM {}: {}".format(kind, texts)
        actions = holder[0].actions()[gmsh + 1:gmsh + 3]
        assert actions[0].icon().cacheKey() != actions[1].icon().cacheKey()
        FreeCADGui.Selection.clearSelection()
        wait(lambda: False, 0.2)
        for a in actions:
            assert not a.isEnabled(), "{} enabled with nothing selected".format(a.text())
            assert "Not available: select exactly one" in a.toolTip(), a.toolTip()
    # the custom FEM toolbar earlier versions wrote is removed, other custom toolbars are kept
    import FreeCAD
    from freecad.hexmerge import init_gui
    base = FreeCAD.ParamGet("User parameter:BaseApp/Workbench/FemWorkbench/Toolbar")
    for group, name in (("Custom_91", "HexMerge"), ("Custom_92", "Mine")):
        bar = base.GetGroup(group)
        bar.SetString("Name", name)
        bar.SetBool("Active", True)
        bar.SetString("HexMerge_MeshHexDominant", "freecad.hexmerge.commands")
        del bar
    init_gui.remove_old_fem_toolbar()
    groups = base.GetGroups()
    assert "Custom_91" not in groups and "Custom_92" in groups, groups
    base.RemGroup("Custom_92")
    print("FEM Mesh menu and toolbar: {} after Gmsh".format(names))
    return actions


def set_combo_view_width(width):
    import FreeCADGui
    from PySide import QtCore, QtGui
    window = FreeCADGui.getMainWindow()
    dock = window.findChild(QtGui.QDockWidget, "Combo View")
    window.resizeDocks([dock], [width], QtCore.Qt.Horizontal)
    wait(lambda: False, 0.5)
    return dock


def check_fits(panel, dock):
    """No widget of the panel is cut off at the dock's width; no horizontal scrolling."""
    from PySide import QtGui
    form = panel.form
    area = [p for p in iter_parents(form) if isinstance(p, QtGui.QScrollArea)]
    width = form.width()
    if area:
        assert not area[0].horizontalScrollBar().isVisible() or \
            area[0].horizontalScrollBar().maximum() == 0, "horizontal scrolling"
        width = min(width, area[0].viewport().width())
    problems = []
    for w in form.findChildren(QtGui.QWidget):
        if not w.isVisibleTo(form) or w.width() == 0:
            continue
        right = w.mapTo(form, w.rect().topRight()).x()
        if right > width + 1:
            problems.append("{} ends at {} > {}".format(w.objectName() or type(w).__name__, right, width))
        fm = w.fontMetrics()
        if isinstance(w, QtGui.QLabel) and not w.wordWrap() and w.text():
            if fm.horizontalAdvance(w.text()) > w.width() + 1:
                problems.append("label '{}' cut".format(w.text()))
        elif isinstance(w, QtGui.QCheckBox):
            if w.sizeHint().width() > w.width() + 1:
                problems.append("checkbox '{}' cut".format(w.text()))
        elif isinstance(w, QtGui.QAbstractSpinBox):
            edit = w.findChild(QtGui.QLineEdit)
            if fm.horizontalAdvance(edit.text()) > edit.width():
                problems.append("spin box {} value '{}' cut".format(w.objectName(), edit.text()))
        elif isinstance(w, QtGui.QComboBox):
            if fm.horizontalAdvance(w.currentText()) + 20 > w.width():
                problems.append("combo {} '{}' cut".format(w.objectName(), w.currentText()))
        elif isinstance(w, QtGui.QTableWidget):
            for r in range(w.rowCount()):
                item = w.item(r, 0)
                icon = 0 if item.icon().isNull() else w.iconSize().width() or 16
                if fm.horizontalAdvance(item.text()) + icon + 6 > w.columnWidth(0):
                    problems.append("table label '{}' cut".format(item.text()))
                for c in (1, 2):
                    item = w.item(r, c)
                    if item and fm.horizontalAdvance(item.text()) + 6 > w.columnWidth(c):
                        problems.append("table value '{}' cut".format(item.text()))
    if problems:
        wide = ["{} {}".format(w.objectName() or type(w).__name__, w.minimumSizeHint().width())
                for w in form.findChildren(QtGui.QWidget)
                if w.isVisibleTo(form) and w.minimumSizeHint().width() > width]
        problems.append("widgets wider than {} px at their minimum: {}".format(width, ", ".join(wide)))
    assert not problems, "at {} px: {}".format(dock.width(), "; ".join(problems))
    print("panel fits the {} px combo view (form {} px wide)".format(dock.width(), form.width()))


def iter_parents(w):
    p = w.parentWidget()
    while p is not None:
        yield p
        p = p.parentWidget()


def check_wheel(panel):
    """A wheel turn over an unfocused spin box changes nothing; focused, it changes the value."""
    from PySide import QtCore, QtGui
    _, box = panel.widgets["MinScaledJacobian"]
    panel.form.tb_advanced.setChecked(True)
    wait(lambda: False, 0.2)

    def turn():
        pos = QtCore.QPointF(box.width() / 2, box.height() / 2)
        event = QtGui.QWheelEvent(pos, box.mapToGlobal(pos.toPoint()), QtCore.QPoint(0, 0),
                                  QtCore.QPoint(0, 120), QtCore.Qt.NoButton,
                                  QtCore.Qt.NoModifier, QtCore.Qt.NoScrollPhase, False)
        QtGui.QApplication.sendEvent(box, event)
        QtGui.QApplication.processEvents()

    box.clearFocus()
    panel.form.pb_apply.setFocus()
    before = box.value()
    turn()
    assert box.value() == before, "wheel changed an unfocused spin box"
    box.setFocus()
    wait(lambda: box.hasFocus(), 2)
    turn()
    assert box.value() != before, "wheel did not change a focused spin box (test is void)"
    box.setValue(before)
    print("wheel: unfocused spin box unchanged, focused one changed")


def open_panel(command, obj_to_select):
    import FreeCADGui
    from freecad.hexmerge.task_mesh_hexdominant import TaskPanelHexDominant
    previous = TaskPanelHexDominant.current
    FreeCADGui.Selection.clearSelection()
    FreeCADGui.Selection.addSelection(obj_to_select)
    FreeCADGui.runCommand(command)
    assert wait(lambda: TaskPanelHexDominant.current not in (None, previous), 10), "no panel"
    panel = TaskPanelHexDominant.current
    # a fresh form: not a dead panel's wrapper (at the same address) with its dead children
    import shiboken2
    assert all(shiboken2.isValid(w) for w in (panel.form, panel.form.w_advanced,
                                              panel.form.l_status)), "a dead widget in a new panel"
    return panel


def finished(panel):
    return lambda: panel.run is not None and not panel.run.running() and panel.form.pb_apply.isEnabled()


def flag_as_qapp(panel):
    """Sets, in every quantity box's PySide wrapper, the "this is the QApplication" bit that
    PySide2 5.15 leaves uninitialised in wrappers of widgets made by FreeCAD's UiLoader: the
    state the intermittent abort came from (shiboken2.delete on such a wrapper deleted FreeCAD's
    QApplication, "free(): invalid size"). Closing the panel must then still not abort. The
    layout (SbkObject.d at 0x20; SbkObjectPrivate: cptr, then the flag bits hasOwnership,
    containsCppWrapper, validCppObject, cppObjectCreated, isQAppSingleton) is checked first."""
    import ctypes
    import shiboken2
    assert shiboken2.__version__.startswith("5.15."), shiboken2.__version__
    boxes = panel.quantity_boxes
    assert boxes, "no quantity boxes in the panel"
    for w in boxes:
        d = ctypes.c_void_p.from_address(id(w) + 0x20).value
        cptr = ctypes.c_void_p.from_address(ctypes.c_void_p.from_address(d).value).value
        flags = ctypes.c_ubyte.from_address(d + 8)
        assert cptr == shiboken2.getCppPointer(w)[0], "unknown shiboken2 layout (pointer)"
        assert bool(flags.value & 4) == shiboken2.isValid(w) and \
            bool(flags.value & 1) == shiboken2.ownedByPython(w), \
            "unknown shiboken2 layout (flags 0x{:02x})".format(flags.value)
        flags.value |= 0x10
    return boxes


def main():
    import FreeCAD
    import FreeCADGui
    from PySide import QtCore, QtGui
    import shiboken2
    import helpers
    from freecad.hexmerge import commands, mesh_hexdominant
    from freecad.hexmerge.task_mesh_hexdominant import TaskPanelHexDominant

    doc, mesh = helpers.box_doc("1st", 8.0, name="HexMergeGui")
    fem_actions = check_fem_menu()
    box = doc.getObject("Box")
    box.ViewObject.Visibility = False

    # commands: inactive with nothing selected, with the reason; Activated changes nothing
    FreeCADGui.Selection.clearSelection()
    assert commands.selected_tet_mesh()[0] is None
    assert not commands.HexDominantFromTetrahedra().IsActive(), "active without selection"
    n = len(doc.Objects)
    commands.HexDominantFromTetrahedra().Activated()
    assert len(doc.Objects) == n
    FreeCADGui.Selection.addSelection(mesh)
    wait(lambda: False, 0.2)
    assert fem_actions[1].isEnabled(), "FEM menu entry disabled with a tet mesh selected"

    # tet mesh: the panel at the default width, wheel guard, Apply, colours, OK
    panel = open_panel("HexMerge_MeshHexDominant", mesh)
    obj = panel.obj
    # with a task panel open (no selection change), the FEM entries say so once hovered
    toolbar = [w for w in fem_actions[1].associatedWidgets() if isinstance(w, QtGui.QToolBar)][0]
    QtGui.QApplication.sendEvent(toolbar, QtCore.QEvent(QtCore.QEvent.Enter))
    assert not fem_actions[1].isEnabled(), "FEM entry enabled while a task panel is open"
    assert "close the open task panel" in fem_actions[1].toolTip(), fem_actions[1].toolTip()
    dock = set_combo_view_width(COMBO_VIEW_WIDTH)
    assert not panel.form.w_advanced.isVisible(), "Advanced is open by default"
    assert panel.form.gb_shape_meshing.isHidden(), "shape options for a tet mesh"
    assert not panel.widgets["TargetSize"][1].isVisibleTo(panel.form), "target size for a tet mesh"
    panel.widgets["MinScaledJacobian"][1].setValue(0.35)
    panel.widgets["MakePyramids"][1].setChecked(True)
    panel.widgets["PyramidsAsHexahedra"][1].setChecked(True)
    panel.apply()
    assert wait(finished(panel), 60), "apply did not finish"
    assert obj.Report, "no report after Apply: " + panel.form.l_status.text()
    assert panel.form.tw_results.rowCount() > 5
    check_fits(panel, dock)
    check_wheel(panel)
    check_fits(panel, dock)  # with Advanced open
    panel.form.tb_advanced.setChecked(False)
    for area in (p for p in iter_parents(panel.form) if isinstance(p, QtGui.QScrollArea)):
        area.verticalScrollBar().setValue(0)  # the screenshot shows the panel's top
    wait(lambda: False, 0.3)
    FreeCADGui.ActiveDocument.activeView().viewIsometric()
    FreeCADGui.SendMsgToActiveView("ViewFit")
    wait(lambda: False, 1.0)
    subprocess.run(["import", "-window", "root", SHOT], check=True)
    check_colors(obj.ViewObject, "first order, mixed")
    boxes = flag_as_qapp(panel)
    panel.accept()
    assert not any(shiboken2.isValid(w) for w in boxes), "OK left a quantity box wrapper valid"
    wait(lambda: False, 0.5)
    assert doc.getObject(obj.Name) is not None, "OK did not keep the object"
    assert abs(obj.MinScaledJacobian - 0.35) < 1e-9
    report = mesh_hexdominant.report_dict(obj)
    assert report["output_cells"] == obj.FemMesh.VolumeCount > 0
    obj.ViewObject.Visibility = False

    # second-order tets recombined: Tet10, Pyra13 (as collapsed Hexa20), Penta15, Hexa20
    mesh2 = doc.getObject("BoxMesh")
    helpers.bench.gmsh(mesh2, 8.0, "2nd")
    import freecad.hexmerge as hm
    quad = hm.make_hexdominant_mesh(doc, mesh2, name="Quadratic", make_pyramids=True)
    wait(lambda: False, 0.5)
    m = quad.FemMesh
    assert m.PrismCount and m.HexaCount and m.TetraCount, (m.PrismCount, m.HexaCount)
    check_colors(quad.ViewObject, "second order, mixed")
    quad.ViewObject.Visibility = False

    # a swept cylinder from its shape, second order: Hexa20 and Penta15
    cylinder = doc.addObject("Part::Cylinder", "Cylinder")
    cylinder.Radius, cylinder.Height = 15, 40
    doc.recompute()
    swept = hm.make_hexdominant_mesh(doc, cylinder, name="Swept", target_size=4)
    wait(lambda: False, 0.5)
    m = swept.FemMesh
    assert m.HexaCount > m.PrismCount > 0 and len(m.getElementNodes(m.Volumes[0])) in (15, 20)
    check_colors(swept.ViewObject, "second order, Hexa20 and Penta15")
    FreeCADGui.ActiveDocument.activeView().viewIsometric()
    FreeCADGui.SendMsgToActiveView("ViewFit")
    wait(lambda: False, 1.0)
    subprocess.run(["import", "-window", "root", SHOT_COLORS], check=True)
    swept.ViewObject.Visibility = False

    # Cancel during the engine, three times: no timer left, no error in the Report view
    # afterwards, the quantity boxes let go of without deleting anything through PySide (their
    # wrappers flagged as the QApplication: see flag_as_qapp), the next panel's boxes usable
    FreeCADGui.Selection.clearSelection()
    big_doc, big = helpers.box_doc("1st", 2.5, name="HexMergeCancel")
    # The engine is held at its "candidates" and "selection" calls until Cancel stops it: on a
    # quiet machine the box's whole run could end between two of this test's polls (CI of
    # 11813b8: the second attempt found the run 'done').
    from freecad.hexmerge import base_taskpanel
    unheld_progress = base_taskpanel.BackgroundRun.progress

    def held_progress(run, message, fraction):
        unheld_progress(run, message, fraction)
        if str(message) in ("candidates", "selection"):
            deadline = time.monotonic() + 30
            while not run.stopped and time.monotonic() < deadline:
                time.sleep(0.01)
        return not run.stopped

    base_taskpanel.BackgroundRun.progress = held_progress
    for attempt in range(3):
        panel = open_panel("HexMerge_MeshHexDominant", big)
        for spec, w in panel.widgets.values():
            if w.objectName().startswith("qsb_"):
                assert shiboken2.isValid(w) and \
                    abs(w.property("rawValue") - spec.value(panel.obj)) < 1e-9, \
                    "quantity box {} unusable in a new panel".format(w.objectName())
        panel.apply()
        assert wait(lambda: panel.run.message in ("candidates", "selection"), 60), \
            "the engine never reached its candidates or selection (message {!r})".format(
                panel.run.message)
        errors_before = len(report_view_errors())
        run = panel.run
        boxes = flag_as_qapp(panel)
        form, advanced = panel.form, panel.form.w_advanced
        panel.reject()
        assert not shiboken2.isValid(form) and not shiboken2.isValid(advanced) and \
            TaskPanelHexDominant.current is None, "Cancel left the form's wrappers for a later panel"
        assert not run.timer.isActive(), "the progress timer still runs after Cancel"
        assert not run.running(), "the engine thread still runs after Cancel"
        assert not any(shiboken2.isValid(w) for w in boxes), "Cancel left a box wrapper valid"
        wait(lambda: False, 3.0 if attempt == 0 else 1.0)
        new_errors = report_view_errors()[errors_before:]
        assert not new_errors, "errors after Cancel: {}".format(new_errors[:3])
        assert not [o for o in big_doc.Objects if o.Name.startswith("HexDominant")], "Cancel kept it"
        print("Cancel {} during '{}': timer stopped, thread ended, no error".format(
            attempt + 1, run.message))
    base_taskpanel.BackgroundRun.progress = unheld_progress
    FreeCAD.closeDocument(big_doc.Name)
    FreeCAD.setActiveDocument(doc.Name)

    # Shape mode: OK without Apply runs in the background, with progress, and closes when done
    panel = open_panel("HexMerge_MeshHexDominantFromShape", box)
    shape_obj = panel.obj
    assert not panel.form.gb_shape_meshing.isHidden(), "no shape options for a shape"
    assert panel.widgets["TargetSize"][1].isVisibleTo(panel.form), "no target size for a shape"
    size = panel.widgets["TargetSize"][1]
    size.setProperty("rawValue", 10.0)
    panel.widgets["SecondOrder"][1].setChecked(False)
    panel.apply()
    assert wait(finished(panel), 60), "apply (shape) did not finish"
    assert panel.form.tw_results.rowCount() > 5, panel.form.l_status.text()
    # a failed run clears the results and says why
    size.setProperty("rawValue", 500.0)
    panel.apply()
    assert wait(lambda: panel.form.pb_apply.isEnabled(), 60)
    assert panel.form.tw_results.rowCount() == 0, "results of the previous run kept after an error"
    assert "larger than the shape" in panel.form.l_status.text(), panel.form.l_status.text()
    # OK without Apply: runs with the new settings in the background, closes when done
    size.setProperty("rawValue", 10.0)
    panel.widgets["SecondOrder"][1].setChecked(True)
    assert panel.accept() is False, "OK closed the panel before the mesh was made"
    assert panel.form.pb_stop.isEnabled() and panel.run.running(), "OK did not run in the background"
    assert wait(lambda: not FreeCADGui.Control.activeDialog(), 60), "OK's run did not close the panel"
    shape_report = mesh_hexdominant.report_dict(shape_obj)
    assert shape_report.get("meshing"), "no meshing report"
    assert shape_report["output_counts"]["hex"] == 72 and shape_obj.FemMesh.HexaCount == 72, \
        shape_report["output_counts"]
    assert len(shape_obj.FemMesh.getElementNodes(shape_obj.FemMesh.Volumes[0])) == 20, "not Hexa20"
    assert shape_obj.Part == box, "the mesh is not linked to its shape (Part)"
    shape_obj.ViewObject.Visibility = True
    FreeCADGui.ActiveDocument.activeView().viewIsometric()
    FreeCADGui.SendMsgToActiveView("ViewFit")
    wait(lambda: False, 1.0)
    check_colors(shape_obj.ViewObject, "Hexa20 box")

    # save and reopen: no error in the Report view
    path = os.path.join(helpers.bench.work_directory("gui_"), "hexmerge_gui.FCStd")
    errors_before = len(report_view_errors())
    shape_name = shape_obj.Name
    doc.saveAs(path)
    FreeCAD.closeDocument(doc.Name)
    doc = FreeCAD.openDocument(path)
    wait(lambda: False, 1.0)
    again = doc.getObject(shape_name)
    assert again.FemMesh.VolumeCount == 72 and again.Part == doc.getObject("Box")
    doc.save()
    wait(lambda: False, 0.5)
    new_errors = report_view_errors()[errors_before:]
    assert not new_errors, "errors on save/reopen: {}".format(new_errors[:3])
    check_colors(again.ViewObject, "Hexa20 box, reopened")
    print("save and reopen: no error")

    for shot in (SHOT, SHOT_COLORS):
        std = subprocess.run(["convert", shot, "-format", "%[fx:standard_deviation]", "info:"],
                             capture_output=True, text=True, check=True).stdout
        assert float(std) > 0.02, "screenshot {} looks blank (std {})".format(shot, std)
    print("GUI TEST PASSED: shape: {}; screenshots {} {}".format(again.Summary, SHOT, SHOT_COLORS))


try:
    main()
except Exception:
    traceback.print_exc()
    print("GUI TEST FAILED")
sys.stdout.flush()
import helpers  # noqa: E402 (HERE is on the path)
helpers.bench.remove_work_directories()  # os._exit skips the exit handlers
os._exit(0)
