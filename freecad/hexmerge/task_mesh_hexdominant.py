# SPDX-License-Identifier: LGPL-2.1-or-later
"""Task panel of the hex-dominant mesh: maps widgets to the object's properties, runs the engine
off the GUI thread on Apply, shows the results. OK keeps, Cancel undoes."""

import os

import FreeCAD
import FreeCADGui
from PySide import QtGui

from . import base_taskpanel
from . import hexmergetools
from . import mesh_hexdominant
from . import properties
from .view_mesh_hexdominant import RESOURCES, TYPE_COLORS

UI_FILE = os.path.join(RESOURCES, "ui", "MeshHexDominant.ui")

CELL_LABELS = ("tetrahedra", "pyramids", "prisms", "hexahedra")
# The 3D view's colour of each type (view provider, ColorByType), shown as a legend in the table.
LABEL_COLORS = dict(zip(CELL_LABELS, (TYPE_COLORS[k] for k in ("tetra", "pyramid", "wedge", "hexahedron"))))


class TaskPanelHexDominant(base_taskpanel.TransactionTaskPanel):

    transaction_name = "Hex-dominant mesh"

    def __init__(self, obj):
        super().__init__(obj)
        TaskPanelHexDominant.current = self  # for macros and the GUI test
        self.form = FreeCADGui.PySideUic.loadUi(UI_FILE)
        self.form.setWindowTitle("Hex-dominant mesh")
        self.run = None
        self.widgets = {}  # property name -> widget
        self.build_parameter_widgets()
        self.form.ckb_pyramids_as_hexahedra.setChecked(bool(obj.PyramidsAsHexahedra))
        self.form.pb_apply.clicked.connect(self.apply)
        self.form.pb_stop.clicked.connect(self.stop)
        self.show_source()
        report = mesh_hexdominant.report_dict(obj)
        if report:
            self.show_results(report)

    # -- widgets <-> properties ---------------------------------------------------------------
    def build_parameter_widgets(self):
        # The mesher's options, shown when the source is a shape, in a group under the source.
        self.gb_shape = QtGui.QGroupBox(properties.SHAPE_GROUP)
        self.gb_shape.setObjectName("gb_shape_meshing")
        self.fl_shape = QtGui.QFormLayout(self.gb_shape)
        self.form.layout().insertWidget(1, self.gb_shape)
        for spec in properties.mesher_specs():
            self.add_widget(spec, self.fl_shape)
        for spec in properties.engine_specs():
            layout = getattr(self.form, "fl_" + spec.group.lower().replace(" ", "_"),
                             self.form.fl_engine)
            self.add_widget(spec, layout)
        if not self.form.fl_engine.rowCount():
            self.form.gb_engine.hide()

    def add_widget(self, spec, layout):
        """One widget for a property, in a form layout, kept in self.widgets."""
        row = spec.row
        label = row.get("label") or spec.name
        if spec.kind == "App::PropertyLength":
            w = FreeCADGui.UiLoader().createWidget("Gui::QuantitySpinBox")
            w.setObjectName("qsb_" + row["name"])
            w.setProperty("unit", "mm")
            w.setProperty("minimum", 0.0)
            w.setProperty("maximum", 1e9)
            w.setProperty("rawValue", spec.value(self.obj))
        elif spec.kind == "App::PropertyAngle":
            w = FreeCADGui.UiLoader().createWidget("Gui::QuantitySpinBox")
            w.setObjectName("qsb_" + row["name"])
            w.setProperty("unit", "deg")
            w.setProperty("minimum", float(row["min"]))
            w.setProperty("maximum", float(row["max"]))
            w.setProperty("rawValue", spec.value(self.obj))
        elif spec.kind == "App::PropertyFloatConstraint":
            w = QtGui.QDoubleSpinBox()
            w.setObjectName("dsb_" + row["name"])
            w.setRange(float(row["min"]), float(row["max"]))
            w.setSingleStep(0.05)
            w.setDecimals(3)
            w.setValue(float(getattr(self.obj, spec.name)))
        elif spec.kind == "App::PropertyIntegerConstraint":
            w = QtGui.QSpinBox()
            w.setObjectName("sb_" + row["name"])
            w.setRange(int(row["min"]), int(row["max"]))
            w.setValue(int(getattr(self.obj, spec.name)))
        elif spec.kind == "App::PropertyBool":
            w = QtGui.QCheckBox()
            w.setObjectName("ckb_" + row["name"])
            w.setChecked(bool(getattr(self.obj, spec.name)))
        else:
            w = QtGui.QComboBox()
            w.setObjectName("cb_" + row["name"])
            w.addItems(list(row["choices"]))
            w.setCurrentIndex(list(row["choices"]).index(getattr(self.obj, spec.name)))
        w.setToolTip(spec.doc)
        l = QtGui.QLabel(label)
        l.setToolTip(spec.doc)
        layout.addRow(l, w)
        self.widgets[spec.name] = (spec, w)
        self.bind_expression(spec.name, w)

    def bind_expression(self, name, widget):
        if widget.objectName().startswith("qsb_"):
            try:
                FreeCADGui.ExpressionBinding(widget).bind(self.obj, name)
            except Exception:
                pass

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
        if self.obj.PyramidsAsHexahedra != self.form.ckb_pyramids_as_hexahedra.isChecked():
            self.obj.PyramidsAsHexahedra = self.form.ckb_pyramids_as_hexahedra.isChecked()

    # -- source and regions -------------------------------------------------------------------
    def show_source(self):
        src = self.obj.SourceMesh
        shape_mode = mesh_hexdominant.is_shape_source(src)
        self.gb_shape.setVisible(shape_mode)
        if src is None:
            self.form.l_source.setText("No source mesh (deleted?)")
            self.form.l_regions.setText("-")
            return
        if shape_mode:
            self.form.gb_source.setTitle("Source shape")
            box = src.Shape.BoundBox
            nsolids = len(src.Shape.Solids)
            self.form.l_source.setText(
                "{}: {} solid{}, {:g} x {:g} x {:g}. Meshed with tetrahedra on a lattice "
                "(OpenCASCADE, TetGen) at the target size, then recombined.".format(
                    src.Label, nsolids, "s" if nsolids > 1 else "", box.XLength, box.YLength,
                    box.ZLength))
            text = ("Regions per solid of {} ({} solids).".format(src.Label, nsolids)
                    if nsolids > 1 else "One region (a single solid).")
            self.form.l_regions.setText(text + " Elements never span two solids unless "
                                        "'Respect regions' is off.")
            return
        m = src.FemMesh
        kind = "Tet10" if m.VolumeCount and m.getElementNodes(m.Volumes[0]).__len__() == 10 else "Tet4"
        self.form.l_source.setText("{}: {} {} tetrahedra, {} nodes ({} output)".format(
            src.Label, m.TetraCount, kind, m.NodeCount,
            "quadratic" if kind == "Tet10" else "linear"))
        groups = [m.getGroupName(g) for g in m.Groups if m.getGroupElementType(g) == "Volume"]
        part = mesh_hexdominant.source_shape(src)
        nsolids = len(part.Shape.Solids) if part is not None else 0
        if groups:
            text = "Regions from the mesh's volume groups: {}.".format(", ".join(groups))
        elif nsolids > 1:
            text = "Regions per solid of {} ({} solids).".format(part.Label, nsolids)
        else:
            text = "One region (no volume groups, a single solid)."
        self.form.l_regions.setText(text + " Tets of different regions are never merged "
                                    "unless 'Respect regions' is off; material groups are "
                                    "written into the new mesh for CalculiX.")

    # -- running ------------------------------------------------------------------------------
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
        shape_mode = mesh_hexdominant.is_shape_source(self.obj.SourceMesh)
        self.form.l_status.setText("Meshing the shape and recombining..." if shape_mode
                                   else "Recombining...")
        self.run = base_taskpanel.BackgroundRun(work, self.on_progress, self.on_done, self.fail)
        self.run.start()

    def stop(self):
        if self.run is not None:
            self.run.stop()
            self.form.l_status.setText("Stopping...")

    def on_progress(self, fraction, message):
        self.form.pgb_progress.setValue(int(round(100 * max(0.0, min(1.0, fraction)))))
        if message:
            self.form.l_status.setText(message)

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
        self.form.l_status.setText("Done: " + self.obj.Summary)
        self.show_results(report)
        FreeCADGui.updateGui()

    def fail(self, error):
        self.set_running(False)
        self.form.pgb_progress.setValue(0)
        if isinstance(error, hexmergetools.Cancelled):
            text = "Cancelled; the mesh is unchanged."
        else:
            text = "Error: {}".format(error)
        self.form.l_status.setText('<span style="color:#b00020">{}</span>'.format(text))
        FreeCAD.Console.PrintError("HexMerge: {}\n".format(text))

    def set_running(self, running):
        self.form.pb_apply.setEnabled(not running)
        self.form.pb_stop.setEnabled(running)

    def accept(self):
        if self.run is not None and self.run.running():
            FreeCAD.Console.PrintWarning("HexMerge: stop the run or wait for it before OK.\n")
            return False
        self.widgets_to_properties()
        if not self.obj.Report or "Touched" in self.obj.State:
            self.doc.recompute()
        return super().accept()

    def reject(self):
        if self.run is not None and self.run.running():
            self.run.stop()
            self.run.thread.join(30)
        return super().reject()

    # -- results ------------------------------------------------------------------------------
    def show_results(self, report):
        rows = results_rows(report)
        t = self.form.tw_results
        t.setRowCount(len(rows))
        for i, row in enumerate(rows):
            for j, text in enumerate(row):
                t.setItem(i, j, QtGui.QTableWidgetItem(text))
            if row[0] in LABEL_COLORS:
                t.item(i, 0).setIcon(color_swatch(LABEL_COLORS[row[0]]))
                t.item(i, 0).setToolTip("Colour of {} in the 3D view".format(row[0]))
        t.resizeColumnsToContents()


def color_swatch(rgb):
    pixmap = QtGui.QPixmap(12, 12)
    pixmap.fill(QtGui.QColor.fromRgbF(*rgb))
    return QtGui.QIcon(pixmap)


def results_rows(report):
    """(quantity, before, after) rows of the results table from an engine report."""
    counts = report.get("output_counts", {})
    if isinstance(counts, (list, tuple)):
        counts = dict(zip(CELL_LABELS, counts))
    counts = {_label(k): v for k, v in counts.items()}
    before = report.get("input_tets", "")
    rows = [("tetrahedra", str(before), str(counts.get("tetrahedra", 0)))]
    for label in CELL_LABELS[1:]:
        rows.append((label, "0", str(counts.get(label, 0))))
    rows.append(("elements", str(before), str(report.get("output_cells", sum(counts.values())))))
    if "element_reduction_percent" in report:
        rows.append(("reduction", "", "{:.1f} %".format(report["element_reduction_percent"])))
    fractions = report.get("volume_fraction", {})
    if isinstance(fractions, (list, tuple)):
        fractions = dict(zip(CELL_LABELS, fractions))
    fractions = {_label(k): v for k, v in fractions.items()}
    for label in ("hexahedra", "prisms"):
        if label in fractions:
            rows.append(("{} volume".format(label[:-1]), "", "{:.1f} %".format(100 * fractions[label])))
    if "nonconforming_quads" in report:
        rows.append(("quads meeting 2 triangles", "", str(report["nonconforming_quads"])))
    mins = report.get("min_scaled_jacobian", {})
    if isinstance(mins, (list, tuple)):
        mins = dict(zip(CELL_LABELS, mins))
    present = [v for k, v in mins.items() if counts.get(_label(k))]
    if present:
        rows.append(("min. scaled Jacobian", "", "{:.3f}".format(min(present))))
    meshing = report.get("meshing")
    if meshing:
        rows.append(("target size", "", "{:g}".format(meshing["parameters"]["size"])))
        rows.append(("max. boundary distance", "", "{:.2g}".format(meshing["max_boundary_distance"])))
        rows.append(("meshing time", "", "{:.2f} s".format(meshing["seconds"])))
    fc = report.get("freecad", {})
    if fc:
        rows.append(("regions", "", "{} ({})".format(fc.get("region_count", 0), fc.get("regions"))))
        rows.append(("pyramids in CalculiX", "",
                     "as C3D8/C3D20" if fc.get("pyramids_as_collapsed_hexahedra") else "left out"))
    return rows


_LABELS = {"tet": "tetrahedra", "tetra": "tetrahedra", "tetra10": "tetrahedra",
           "pyramid": "pyramids", "pyramid13": "pyramids", "prism": "prisms", "wedge": "prisms",
           "wedge15": "prisms", "hex": "hexahedra", "hexahedron": "hexahedra",
           "hexahedron20": "hexahedra"}


def _label(key):
    return _LABELS.get(str(key).lower(), str(key))
