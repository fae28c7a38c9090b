# SPDX-License-Identifier: LGPL-2.1-or-later
"""Task panel of the hex-dominant mesh: maps widgets to the object's properties, runs the job off
the GUI thread on Apply (and on OK when nothing was applied), shows the results. OK keeps, Cancel
undoes. Imports its job and base panel, never the view provider (which opens it)."""

import FreeCAD
import FreeCADGui
from PySide import QtCore, QtGui

from . import base_taskpanel
from . import colors
from . import engine
from . import mesh_hexdominant
from . import properties
from . import results
from .resources import resource_path

UI_FILE = resource_path("ui", "MeshHexDominant.ui")

# Where each property's widget goes. Common settings (a FEM user's) in "mesh" and "materials";
# the rest (the engine's and the mesher's research settings) in the folded "Advanced" part.
COMMON = {
    "TargetSize": "mesh", "SecondOrder": "mesh", "MakeHexahedra": "mesh", "MakePrisms": "mesh",
    "MakePyramids": "mesh", "Conformity": "mesh",
    "RespectRegions": "materials", "PyramidsAsHexahedra": "materials",
    "LinearHexahedron": "materials", "QuadraticHexahedron": "materials",
    "QuadraticPyramid": "materials",
}
TOLERANCES = ("MinDihedralAngle", "MinBoundaryDihedralAngle", "MaxFaceAngle", "MinScaledJacobian")
LABELS = {"PyramidsAsHexahedra": "Pyramids as hexahedra",
          "SecondOrder": "Second order (Tet10, Hexa20, ...)",
          "RespectRegions": "Keep regions apart"}

# Engine and mesher phases -> (readable name, start, end) on one bar of 0..1. In shape mode the
# meshing takes the first part and the recombination's phases are scaled into the rest.
PHASES = {
    "mesh shape": ("Meshing the shape (OpenCASCADE, TetGen)", 0.0, 1.0),
    "topology": ("Reading the tetrahedra", 0.0, 0.05),
    "candidates": ("Finding hexahedra, prisms, pyramids", 0.05, 0.6),
    "selection": ("Choosing the elements", 0.6, 0.95),
    "bound": ("Optimality bound (GLPK)", 0.95, 0.99),
    "done": ("Writing the mesh", 1.0, 1.0),
}
SHAPE_MESHING_SHARE = 0.4
# The mesher's steps ("mesh shape: <step>", then " (<way of placing the points>)" after the
# first way) -> readable names.
MESHER_STEPS = {
    "surface": "surface triangulation", "lattice": "lattice", "core": "hexahedral core",
    "layers": "boundary layers", "tetgen": "tetrahedra (TetGen)", "regions": "regions",
    "slivers": "improving the tetrahedra", "check": "boundary check", "second order": "second order",
}


def overall_progress(phase, fraction, shape_mode):
    """(fraction of the whole run in [0, 1], readable phase name) for an engine progress call."""
    if phase.startswith("mesh shape: "):
        step, _, way = phase[len("mesh shape: "):].partition(" (")
        name = f"Meshing the shape: {MESHER_STEPS.get(step, step)}"
        if way:
            name += f" ({way}"
        return SHAPE_MESHING_SHARE * max(0.0, min(1.0, fraction)), name
    name, start, end = PHASES.get(phase, (phase, 0.0, 1.0))
    f = start + (end - start) * max(0.0, min(1.0, fraction))
    if not shape_mode:
        return f, name
    if phase == "mesh shape":
        return SHAPE_MESHING_SHARE * f, name
    return SHAPE_MESHING_SHARE + (1.0 - SHAPE_MESHING_SHARE) * f, name


class TaskPanelHexDominant(base_taskpanel.TransactionTaskPanel):

    transaction_name = "Hex-dominant mesh"
    current = None  # the open panel, for macros and the GUI test

    def __init__(self, obj):
        super().__init__(obj)
        self.form = FreeCADGui.PySideUic.loadUi(UI_FILE)
        self.form.setWindowTitle("Hex-dominant mesh")
        self.run = None
        self.accept_when_done = False
        self.shape_mode_running = False
        self.wheel_guard = base_taskpanel.WheelGuard(self.form)
        self.loader = FreeCADGui.UiLoader()  # kept: its widgets die with it
        self.widgets = {}  # property name -> (spec, widget)
        self.quantity_boxes = []  # the Gui::QuantitySpinBox wrappers, see release_wrappers
        self.shape_only = []  # widgets shown only for a shape source
        self.build_parameter_widgets()
        self.set_up_results_table()
        self.form.tb_advanced.toggled.connect(self.show_advanced)
        self.show_advanced(False)
        self.form.pb_apply.clicked.connect(self.apply)
        self.form.pb_stop.clicked.connect(self.stop)
        self.form.destroyed.connect(self.form_destroyed)
        self.show_source()
        report = mesh_hexdominant.report_dict(obj)
        if report:
            self.show_results(report)
        TaskPanelHexDominant.current = self  # only once built: a failed panel is never current

    # -- widgets <-> properties ---------------------------------------------------------------
    def build_parameter_widgets(self):
        for spec in properties.all_specs():
            if spec.name == "SourceMesh" or spec.name not in self.obj.PropertiesList:
                continue
            if spec.name in COMMON:
                layout = getattr(self.form, "fl_" + COMMON[spec.name])
            elif spec.name in TOLERANCES:
                layout = self.form.fl_tolerances
            elif spec.group == properties.SHAPE_GROUP:
                layout = self.form.fl_shape_meshing
            else:
                layout = self.form.fl_engine
            self.add_widget(spec, layout)
        for fl in (self.form.fl_mesh, self.form.fl_materials, self.form.fl_tolerances,
                   self.form.fl_engine, self.form.fl_shape_meshing):
            fl.setRowWrapPolicy(QtGui.QFormLayout.WrapLongRows)
            fl.setFieldGrowthPolicy(QtGui.QFormLayout.AllNonFixedFieldsGrow)

    def add_widget(self, spec, layout):
        """One widget for a property, in a form layout, kept in self.widgets."""
        row = spec.row or {}
        label = LABELS.get(spec.name) or row.get("label") or spec.name
        unit = row.get("unit")
        if unit == "h":
            label += " (\u00d7 h)"  # a fraction of the target size
        elif unit == "s":
            label += " (s)"
        if spec.kind in ("App::PropertyLength", "App::PropertyAngle"):
            w = self.loader.createWidget("Gui::QuantitySpinBox")
            self.quantity_boxes.append(w)
            w.setObjectName("qsb_" + spec.name)
            length = spec.kind == "App::PropertyLength"
            w.setProperty("unit", "mm" if length else "deg")
            w.setProperty("minimum", 0.0 if length else float(row["min"]))
            w.setProperty("maximum", 1e9 if length else float(row["max"]))
            w.setProperty("rawValue", spec.value(self.obj))
        elif spec.kind == "App::PropertyFloatConstraint":
            w = QtGui.QDoubleSpinBox()
            w.setObjectName("dsb_" + spec.name)
            w.setRange(float(row["min"]), float(row["max"]))
            w.setSingleStep(0.05)
            w.setDecimals(3)
            w.setValue(float(getattr(self.obj, spec.name)))
        elif spec.kind == "App::PropertyIntegerConstraint":
            w = QtGui.QSpinBox()
            w.setObjectName("sb_" + spec.name)
            w.setRange(int(row["min"]), int(row["max"]))
            w.setValue(int(getattr(self.obj, spec.name)))
        elif spec.kind == "App::PropertyBool":
            w = QtGui.QCheckBox(label)
            w.setObjectName("ckb_" + spec.name)
            w.setChecked(bool(getattr(self.obj, spec.name)))
        else:
            w = QtGui.QComboBox()
            w.setObjectName("cb_" + spec.name)
            w.addItems(list(row["choices"]))
            w.setCurrentIndex(list(row["choices"]).index(getattr(self.obj, spec.name)))
            w.setSizeAdjustPolicy(QtGui.QComboBox.AdjustToMinimumContentsLengthWithIcon)
            w.setMinimumContentsLength(8)
        w.setToolTip(spec.doc)
        shown = [w]
        if isinstance(w, QtGui.QCheckBox):
            layout.addRow(w)
        else:
            self.wheel_guard.guard(w)
            w.setSizePolicy(QtGui.QSizePolicy.Expanding, QtGui.QSizePolicy.Fixed)
            w.setMinimumWidth(0)
            l = QtGui.QLabel(label)
            l.setToolTip(spec.doc)
            layout.addRow(l, w)
            shown.append(l)
        if spec.group == properties.SHAPE_GROUP:
            self.shape_only.extend(shown)
        self.widgets[spec.name] = (spec, w)
        self.bind_expression(spec.name, w)

    def bind_expression(self, name, widget):
        if widget.objectName().startswith("qsb_"):
            FreeCADGui.ExpressionBinding(widget).bind(self.obj, name)

    def widgets_to_properties(self):
        for name, (spec, w) in self.widgets.items():
            if isinstance(w, QtGui.QCheckBox):
                value = w.isChecked()
            elif isinstance(w, QtGui.QComboBox):
                value = w.currentText()
            elif isinstance(w, (QtGui.QDoubleSpinBox, QtGui.QSpinBox)):
                value = w.value()
            elif spec.kind == "App::PropertyLength":
                value = float(w.property("rawValue"))
                if abs(spec.value(self.obj) - value) > 1e-12 * max(1.0, abs(value)):
                    setattr(self.obj, name, value)
                continue
            else:
                value = FreeCAD.Units.Quantity(w.property("rawValue"), FreeCAD.Units.Unit("deg"))
            if getattr(self.obj, name) != value:
                setattr(self.obj, name, value)

    def show_advanced(self, shown):
        self.form.w_advanced.setVisible(shown)
        self.form.tb_advanced.setArrowType(QtCore.Qt.DownArrow if shown else QtCore.Qt.RightArrow)

    # -- source and regions -------------------------------------------------------------------
    def shape_mode(self):
        return mesh_hexdominant.is_shape_source(self.obj.SourceMesh)

    def show_source(self):
        src = self.obj.SourceMesh
        shape_mode = self.shape_mode()
        for w in self.shape_only:
            w.setVisible(shape_mode)
        self.form.gb_shape_meshing.setVisible(shape_mode)
        if src is None:
            self.form.l_source.setText("No source (deleted?)")
            self.form.l_regions.setText("-")
            return
        if shape_mode:
            box = src.Shape.BoundBox
            nsolids = len(src.Shape.Solids)
            self.form.l_source.setText(
                "Shape {}: {} solid{}, {:g} \u00d7 {:g} \u00d7 {:g} mm".format(
                    src.Label, nsolids, "s" if nsolids > 1 else "", box.XLength, box.YLength,
                    box.ZLength))
            self.form.l_source.setToolTip(
                "Meshed with tetrahedra on a lattice (OpenCASCADE, TetGen) at the target size, "
                "then recombined")
            text = ("Regions: the {} solids.".format(nsolids) if nsolids > 1
                    else "One region (a single solid).")
            found, not_honoured = mesh_hexdominant.found_mesh_regions(self.obj)
            if found:
                text += "\nMesh regions and boundary layers: " + "; ".join(found)
            if not_honoured:
                text += "\nNot honoured: " + "; ".join(not_honoured)
            self.form.l_regions.setText(text)
            return
        m = src.FemMesh
        kind = "Tet10" if m.VolumeCount and len(m.getElementNodes(m.Volumes[0])) == 10 else "Tet4"
        self.form.l_source.setText("Mesh {}: {} {}, {} nodes ({} output)".format(
            src.Label, m.TetraCount, kind, m.NodeCount,
            "second-order" if kind == "Tet10" else "first-order"))
        groups = [m.getGroupName(g) for g in m.Groups if m.getGroupElementType(g) == "Volume"]
        part = mesh_hexdominant.source_shape(src)
        nsolids = len(part.Shape.Solids) if part is not None else 0
        if groups:
            text = "Regions: the mesh's volume groups ({}).".format(", ".join(groups))
        elif nsolids > 1:
            text = "Regions: the {} solids of {}.".format(nsolids, part.Label)
        else:
            text = "One region (no volume groups, a single solid)."
        self.form.l_regions.setText(text)
        self.form.l_regions.setToolTip(
            "Tetrahedra of different regions are never merged unless 'Keep regions apart' is off; "
            "material groups are written into the new mesh for CalculiX.")

    # -- running ------------------------------------------------------------------------------
    def needs_run(self):
        state = self.obj.State
        return not self.obj.Report or "Touched" in state or "Invalid" in state

    def apply(self):
        if self.run is not None and self.run.running():
            return
        self.widgets_to_properties()
        try:
            job = mesh_hexdominant.prepare(self.obj)
        except Exception as e:
            self.fail(e)
            return

        def work(progress):
            job.run(progress)
            return job

        self.set_running(True)
        self.shape_mode_running = self.shape_mode()
        self.on_progress(0.0, "mesh shape" if self.shape_mode_running else "topology")
        self.run = base_taskpanel.BackgroundRun(work, self.on_progress, self.on_done, self.fail)
        self.run.start()

    def stop(self):
        if self.run is not None and self.run.running():
            self.run.stop()
            self.set_status("Stopping...")

    def shut_down(self):
        """Stops the run and its timer for good (the panel is closing)."""
        if self.run is not None:
            self.run.cancel()

    def form_destroyed(self, *args):
        """However the panel goes (OK, Cancel, the document closed), its run stops and PySide
        lets go of the form's widgets."""
        self.shut_down()
        self.release_wrappers()

    def release_wrappers(self):
        """Detaches PySide from the widgets FreeCAD made (the form from its .ui file, the named
        children FreeCAD's loader hangs on it as attributes, the Gui::QuantitySpinBox widgets)
        before the form goes; Qt deletes them with the form. PySide is not told when Qt deletes
        such widgets, so while this panel object lives (a macro's variable, `current`), a later
        panel's widget at the same address would get the dead one's wrapper: for the form, with
        the old children as attributes ("Internal C++ object already deleted"). shiboken2.
        invalidate marks each wrapper dead and drops it from PySide's address table without
        touching the widget.

        Not shiboken2.delete: PySide2 5.15 leaves the "this is the QApplication" bit of such a
        wrapper uninitialised (heap garbage), and delete() on a wrapper with the bit set deletes
        FreeCAD's QApplication instead of the widget: the intermittent abort "free(): invalid
        size" (docs/freecad.md)."""
        import shiboken2
        if TaskPanelHexDominant.current is self:
            TaskPanelHexDominant.current = None
        if self.form is None:
            return
        children = [w for w in vars(self.form).values() if isinstance(w, QtCore.QObject)]
        for w in self.quantity_boxes + children + [self.form]:
            if shiboken2.isValid(w):
                shiboken2.invalidate(w)
        self.quantity_boxes = []
        self.form = None

    def on_progress(self, fraction, phase):
        if not phase:
            return
        value, name = overall_progress(phase, fraction, self.shape_mode_running)
        self.form.pgb_progress.setValue(int(round(100 * value)))
        self.set_status(name + "...")

    def on_done(self, job):
        self.set_running(False)
        try:
            femmesh, report = job.finish()
            report["freecad"]["source"] = self.obj.SourceMesh.Name
            mesh_hexdominant.store(self.obj, femmesh, report)
            self.obj.purgeTouched()  # the stored mesh is this object's recompute result
        except Exception as e:
            self.fail(e)
            return
        self.form.pgb_progress.setValue(100)
        warnings = report["freecad"].get("warnings", [])
        self.set_status("Done: " + self.obj.Summary
                        + "".join("\nWarning: " + w for w in warnings))
        self.show_results(report)
        if self.accept_when_done:
            self.accept_when_done = False
            self.release_wrappers()
            super().accept()

    def fail(self, error):
        self.set_running(False)
        self.accept_when_done = False
        self.form.pgb_progress.setValue(0)
        self.form.tw_results.setRowCount(0)
        if isinstance(error, engine.Cancelled):
            text = "Stopped; the mesh is unchanged."
        else:
            text = "Error: {}".format(error)
            FreeCAD.Console.PrintError("HexMerge: {}\n".format(text))
        self.set_status(text, error=True)

    def set_status(self, text, error=False):
        self.form.l_status.setText(text)
        self.form.l_status.setStyleSheet("color: #b00020" if error else "")

    def set_running(self, running):
        self.form.pb_apply.setEnabled(not running)
        self.form.pb_stop.setEnabled(running)

    def accept(self):
        """OK: keeps the mesh. Settings not applied yet are applied first, like Apply (off the
        GUI thread, with progress and Stop); the panel closes when that run succeeds."""
        if self.run is not None and self.run.running():
            self.set_status("Running: wait for it, or Stop.")
            return False
        self.widgets_to_properties()
        if self.needs_run():
            self.accept_when_done = True
            self.apply()
            return False
        self.shut_down()
        self.release_wrappers()
        return super().accept()

    def reject(self):
        self.shut_down()
        self.release_wrappers()
        return super().reject()

    # -- results ------------------------------------------------------------------------------
    def set_up_results_table(self):
        t = self.form.tw_results
        t.verticalHeader().hide()
        t.verticalHeader().setDefaultSectionSize(t.fontMetrics().height() + 6)
        header = t.horizontalHeader()
        header.setSectionResizeMode(0, QtGui.QHeaderView.Stretch)
        header.setSectionResizeMode(1, QtGui.QHeaderView.ResizeToContents)
        header.setSectionResizeMode(2, QtGui.QHeaderView.ResizeToContents)
        t.setRowCount(0)
        self.fit_table_height()

    def fit_table_height(self):
        t = self.form.tw_results
        rows = sum(t.rowHeight(i) for i in range(t.rowCount()))
        t.setFixedHeight(t.horizontalHeader().height() + rows + 2 * t.frameWidth())
        t.setVisible(t.rowCount() > 0)

    def show_results(self, report):
        rows = results.results_rows(report)
        t = self.form.tw_results
        t.setRowCount(len(rows))
        for i, row in enumerate(rows):
            for j, text in enumerate(row):
                item = QtGui.QTableWidgetItem(text)
                item.setToolTip(results.ROW_DOCS.get(row[0], text) if j == 0 else text)
                t.setItem(i, j, item)
            if row[0] in colors.LABEL_COLORS:
                t.item(i, 0).setIcon(color_swatch(colors.LABEL_COLORS[row[0]]))
                t.item(i, 0).setToolTip("Colour of {} in the 3D view".format(row[0]))
        self.fit_table_height()


def color_swatch(rgb):
    pixmap = QtGui.QPixmap(12, 12)
    pixmap.fill(QtGui.QColor.fromRgbF(*rgb))
    return QtGui.QIcon(pixmap)
