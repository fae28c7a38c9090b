# SPDX-License-Identifier: LGPL-2.1-or-later
"""Task-panel base classes: one owns the undo transaction, one runs work off the GUI thread."""

import threading
import traceback

import FreeCAD
import FreeCADGui
from PySide import QtCore, QtGui


class TransactionTaskPanel:
    """OK commits the document's transaction, Cancel aborts it (undoing what the command and the
    panel did). Opens a transaction when the panel is opened on an existing object."""

    transaction_name = "Edit"

    def __init__(self, obj):
        self.obj = obj
        self.doc = obj.Document
        if not getattr(self.doc, "HasPendingTransaction", False):
            self.doc.openTransaction(self.transaction_name)

    def getStandardButtons(self):
        return int(QtGui.QDialogButtonBox.Ok | QtGui.QDialogButtonBox.Cancel)

    def accept(self):
        self.doc.commitTransaction()
        self.close()
        return True

    def reject(self):
        self.doc.abortTransaction()
        self.doc.recompute()
        self.close()
        return True

    def close(self):
        FreeCADGui.Control.closeDialog()
        gdoc = FreeCADGui.getDocument(self.doc.Name)
        if gdoc is not None and gdoc.getInEdit() is not None:
            gdoc.resetEdit()


class WheelGuard(QtCore.QObject):
    """Event filter: a spin box or combo box takes the mouse wheel only when it has the focus, so
    scrolling the panel never changes the value under the pointer. Install with guard(widget)."""

    def eventFilter(self, widget, event):
        if event.type() == QtCore.QEvent.Wheel and not widget.hasFocus():
            parent = widget.parentWidget()
            if parent is not None:  # the panel's scroll area scrolls instead
                QtCore.QCoreApplication.sendEvent(parent, event)
            return True
        return False

    def guard(self, widget):
        widget.setFocusPolicy(QtCore.Qt.StrongFocus)
        widget.installEventFilter(self)


class BackgroundRun:
    """Runs work(progress) on a Python thread; the GUI polls it with a QTimer.

    progress(message, fraction) is handed to the work and returns False once stop() was called,
    which is how the engine is cancelled. on_progress(fraction, message), on_done(result) and
    on_error(exception) are called on the GUI thread, never after cancel().
    """

    def __init__(self, work, on_progress, on_done, on_error, interval_ms=100):
        self.work = work
        self.on_progress = on_progress
        self.on_done = on_done
        self.on_error = on_error
        self.fraction = 0.0
        self.message = ""
        self.result = None
        self.error = None
        self.trace = ""
        self.stopped = False
        self.cancelled = False
        self.thread = threading.Thread(target=self._main, daemon=True)
        self.timer = QtCore.QTimer()
        self.timer.setInterval(interval_ms)
        self.timer.timeout.connect(self._poll)

    def start(self):
        self.thread.start()
        self.timer.start()

    def stop(self):
        """Asks the work to stop at its next progress call; on_error gets Cancelled."""
        self.stopped = True

    def cancel(self, wait_s=30.0):
        """Stops the work and the timer for good (the panel is closing): no callback runs after
        this. Waits up to wait_s for the thread, which ends at the engine's next progress call."""
        self.stopped = True
        self.cancelled = True
        self.timer.stop()
        try:
            self.timer.timeout.disconnect(self._poll)
        except (RuntimeError, TypeError):  # already disconnected
            pass
        self.thread.join(wait_s)

    def running(self):
        return self.thread.is_alive()

    def progress(self, message, fraction):
        """The engine's callback: (phase name, fraction done in [0, 1])."""
        self.message = str(message)
        self.fraction = float(fraction)
        return not self.stopped

    def _main(self):
        try:
            self.result = self.work(self.progress)
        except BaseException as e:  # reported on the GUI thread
            self.error = e
            self.trace = traceback.format_exc()

    def _poll(self):
        if self.cancelled:
            self.timer.stop()
            return
        self.on_progress(self.fraction, self.message)
        if self.thread.is_alive():
            return
        self.timer.stop()
        if self.error is not None:
            FreeCAD.Console.PrintLog(self.trace)
            self.on_error(self.error)
        else:
            self.on_done(self.result)
