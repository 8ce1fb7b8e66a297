"""The advice panel: what the advisor measured on the mesh or point cloud, its ranking of the candidate
calls (the recommendation first and highlighted) with the error the study's table predicts and the
error measured on noisy copies of the input's smooth twin (with its spread over the copies; the calls
the copies cannot tell from the recommendation marked ≈), and Apply, which puts the selected row
into the active pane. While the advisor runs, a progress bar and Cancel. Advice computed for an
earlier input is shown as stale and cannot be applied."""

from __future__ import annotations

from html import escape

from curv.core.errors import EstimatorError
from curv.estimators import ESTIMATORS
from PySide6.QtCore import Qt, Signal
from PySide6.QtGui import QBrush, QColor, QFont
from PySide6.QtWidgets import (
    QAbstractItemView, QFormLayout, QGroupBox, QHBoxLayout, QHeaderView, QLabel, QProgressBar, QPushButton,
    QSizePolicy, QTableWidget, QTableWidgetItem, QToolButton, QVBoxLayout, QWidget,
)

from app.model import FEATURE_LABELS, Document, Pane, feature_rows, pane_letter, ranking_rows
from app.model.advice import CLOUD_FEATURE_LABELS, RankingRow, check_text

from .inspect_panel import RANGE_TIP, estimator_tooltip

__all__ = ["AdvicePanel", "RECOMMENDED_BACKGROUND"]

RECOMMENDED_BACKGROUND = "#dcefd8"
"""Background of the recommended row of the ranking."""

STALE_COLOUR = "#a15c00"
ERROR_COLOUR = "#b00020"

INTRO = ("Advise measures the mesh (noise, irregularity, density, borders, polygons), ranks every "
         "estimator and range by the median relative error the paper's study predicts for such a mesh, then "
         "checks the first of them on noisy copies of the mesh's own smooth twin and on the mesh itself, and "
         "ranks them by the predicted error and the error on the mesh itself against its twin (realized) "
         "together. On a point cloud every candidate is checked and ranks by the error measured on the copies.")
ERREL_TIP = ("Predicted median relative error e_rel (paper eq. 5.2) of this call on a mesh with the measured "
             "features, from the study's results on its test surfaces (none on a point cloud). Lower is better.")
MEASURED_TIP = ("Median relative error e_rel measured on noisy copies of the input's smooth twin (the input's "
                "sampling or connectivity, its noise removed by wide polynomial fits, so its curvature is exact), "
                "with the noise measured on the input put back: the geometric mean over the copies, and × its "
                "spread over them (a factor). ≈: within noise of the recommendation (it did as well on at least "
                "one copy). Empty: not checked. On a point cloud checked calls rank by this, the others after them; on "
                "a mesh the predicted and the realized error decide (the summary above says so).")
OPTIONS_TIP = ("Options of the call besides estimator and range: the jet's degree (deg 4), or normals from a "
               "local jet fit at a range (fit R4: normals=\"fit\", fit_range=4). Apply sets them in the pane too.")
VALID_TIP = ("Share of this mesh's vertices the call gives a value at: border vertices, supports with fewer "
             "vertices than the fit's unknowns and, for the closed-ring estimators, supports that reach a border "
             "are lost. Calls that lose more than 2 % more of the mesh than the best one rank after the rest.")
COLUMNS = (("Estimator", "Registry name of the estimator (hover a row for its method)"),
           ("Range", RANGE_TIP),
           ("Measured", MEASURED_TIP),
           ("Valid", VALID_TIP),
           ("Predicted", ERREL_TIP),
           ("Options", OPTIONS_TIP))
"""The ranking's columns, in order: what the ranking goes by (the measured error with its spread) comes
right after the call, where a dock as narrow as 360 px still shows it; the options' words last."""
COLUMN = {title: c for c, (title, _) in enumerate(COLUMNS)}
"""Column index by title."""


class AdvicePanel(QWidget):
    """Shows :attr:`Document.advice` for the document's mesh; ``apply_requested`` asks for a row.

    Parameters
    ----------
    doc : Document

    Signals
    -------
    apply_requested(Pane)
        Show this (validated) estimator and range in the active pane and compute it.
    cancel_requested()
        Stop the advisor.
    """

    apply_requested = Signal(object)
    cancel_requested = Signal()

    def __init__(self, doc: Document, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self._running = False
        self._rows: list[RankingRow] = []
        self._shown_record = None  # the record the table holds (refilled only when it changes)

        self.status = QLabel()
        self.status.setWordWrap(True)
        self.status.setTextFormat(Qt.TextFormat.RichText)
        self.advise_button = QToolButton()
        self.advise_button.setToolButtonStyle(Qt.ToolButtonStyle.ToolButtonTextOnly)
        self.progress = QProgressBar()
        self.progress.setRange(0, 1000)
        self.progress.setTextVisible(True)
        self.progress.setToolTip("The advisor's progress: measuring the input, building its smooth twin, "
                                 "checking the candidates on noisy copies")
        self.cancel_button = QPushButton("Cancel")
        self.cancel_button.setToolTip("Stop the advisor (the advice shown before stays)")
        self.cancel_button.clicked.connect(self.cancel_requested)
        self.check = QLabel()
        self.check.setWordWrap(True)
        self.check.setTextFormat(Qt.TextFormat.PlainText)
        self.check.setObjectName("advice_check")
        self.check.setToolTip("What the self-check did: how many calls it measured on how many noisy copies, "
                              "and the noise it measured on the input")
        self.why = QLabel()
        self.why.setWordWrap(True)
        self.why.setObjectName("advice_why")
        self.why.setStyleSheet("#advice_why { background: palette(alternate-base); border: 1px solid palette(mid);"
                               " border-radius: 3px; padding: 4px; }")
        self.why.setToolTip("The advisor's summary: what it measured and what it recommends")
        self.why.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)

        self.features_box = QGroupBox("Measured on the mesh")
        self._features_form = QFormLayout(self.features_box)
        self._features_form.setRowWrapPolicy(QFormLayout.RowWrapPolicy.WrapLongRows)
        self.feature_labels: dict[str, QLabel] = {}
        self.feature_values: dict[str, QLabel] = {}
        for name in dict.fromkeys((*FEATURE_LABELS, *CLOUD_FEATURE_LABELS)):
            label, value = QLabel(name), QLabel()
            value.setWordWrap(True)
            value.setTextInteractionFlags(Qt.TextInteractionFlag.TextSelectableByMouse)
            self._features_form.addRow(label, value)
            self.feature_labels[name], self.feature_values[name] = label, value

        self.ranking_box = QGroupBox("Ranking by predicted error")
        self.table = QTableWidget(0, len(COLUMNS))
        for col, (title, tip) in enumerate(COLUMNS):
            item = QTableWidgetItem(title)
            item.setToolTip(tip)
            self.table.setHorizontalHeaderItem(col, item)
        self.table.setSelectionBehavior(QAbstractItemView.SelectionBehavior.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SelectionMode.SingleSelection)
        self.table.setEditTriggers(QAbstractItemView.EditTrigger.NoEditTriggers)
        self.table.setWordWrap(False)
        self.table.verticalHeader().setSectionResizeMode(QHeaderView.ResizeMode.Fixed)
        self.table.verticalHeader().setDefaultSectionSize(self.fontMetrics().height() + 6)
        self.table.verticalHeader().setToolTip("Rank; ★ marks the recommendation")
        header = self.table.horizontalHeader()
        for c in range(len(COLUMNS) - 1):
            header.setSectionResizeMode(c, QHeaderView.ResizeMode.ResizeToContents)
        header.setSectionResizeMode(len(COLUMNS) - 1, QHeaderView.ResizeMode.Stretch)
        # in a narrow dock the options' words scroll into view rather than being cut off unseen
        self.table.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAsNeeded)
        self.table.setMinimumHeight(5 * (self.fontMetrics().height() + 6))  # the header and four rows
        # the table takes the height left over (its own scroll bar), never asks for more: the dock's
        # scroll area would otherwise add a second scroll bar around the whole panel
        self.table.setSizePolicy(QSizePolicy.Policy.Expanding, QSizePolicy.Policy.Ignored)
        self.apply_button = QPushButton("Apply")
        ranking_lay = QVBoxLayout(self.ranking_box)
        ranking_lay.addWidget(self.table, 1)
        ranking_lay.addWidget(self.apply_button)

        top = QHBoxLayout()
        top.addWidget(self.status, 1)
        top.addWidget(self.advise_button, 0, Qt.AlignmentFlag.AlignTop)
        running = QHBoxLayout()
        running.addWidget(self.progress, 1)
        running.addWidget(self.cancel_button)
        self._running_row = QWidget()
        self._running_row.setLayout(running)
        running.setContentsMargins(0, 0, 0, 0)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(4, 4, 4, 4)
        lay.addLayout(top)
        lay.addWidget(self._running_row)
        lay.addWidget(self.why)
        lay.addWidget(self.check)
        # the ranking and its Apply before the measurements: on a 768 px screen the dock shows the
        # choice without scrolling, the measured features below it are what a person reads next
        lay.addWidget(self.ranking_box, 1)
        lay.addWidget(self.features_box)
        lay.addStretch(0)  # takes the height only while the ranking is hidden: the text stays on top

        self.table.itemSelectionChanged.connect(self._update_apply)
        self.table.cellDoubleClicked.connect(lambda row, col: self.apply_row(row))
        self.apply_button.clicked.connect(lambda: self.apply_row(self.selected_row()))
        doc.advice_changed.connect(lambda record: self.refresh())
        doc.mesh_changed.connect(lambda change: self.refresh())
        doc.panes_changed.connect(self._update_apply)
        doc.pane_changed.connect(lambda i: self._update_apply())
        self.refresh()

    # -- state ------------------------------------------------------------------------------------
    @property
    def rows(self) -> list[RankingRow]:
        """The ranking the table shows, top to bottom."""
        return list(self._rows)

    @property
    def is_stale(self) -> bool:
        """The panel shows advice that was computed for an earlier mesh."""
        record = self.doc.advice
        return record is not None and record.advice is not None and not self.doc.advice_current

    def selected_row(self) -> int:
        """Index of the selected ranking row (the recommendation, 0, when nothing is selected)."""
        rows = self.table.selectionModel().selectedRows()
        return rows[0].row() if rows else 0

    def select_row(self, row: int) -> None:
        """Select ranking row ``row`` (what Apply then applies)."""
        self.table.selectRow(row)

    def set_running(self, running: bool) -> None:
        """The advisor started or stopped: say so above the advice, show or hide its progress."""
        self._running = bool(running)
        if running:
            self.set_progress(-1.0, "measuring the input")
        self.refresh()

    def set_progress(self, fraction: float, text: str = "") -> None:
        """The advisor's progress: ``fraction`` done (negative: not known yet) and what runs."""
        if fraction < 0:
            self.progress.setRange(0, 0)  # a busy indicator
        else:
            self.progress.setRange(0, 1000)
            self.progress.setValue(int(round(1000 * min(max(fraction, 0.0), 1.0))))
        self.progress.setFormat(f"{text} %p%" if text and fraction >= 0 else (text or "%p%"))

    # -- user -> window ---------------------------------------------------------------------------
    def apply_row(self, row: int) -> None:
        """Ask for ranking row ``row`` in the active pane, if the advice is for the mesh shown now."""
        if not self.doc.advice_current or not 0 <= row < len(self._rows):
            return
        chosen = self._rows[row]
        try:
            pane = Pane(chosen.method, chosen.range if chosen.range is not None else 2, radius=chosen.radius,
                        knn=chosen.knn, options=chosen.options).validated()
        except (EstimatorError, KeyError) as exc:  # an estimator of the study this curv does not register
            self.status.setText(f"<span style='color:{ERROR_COLOUR}'>Cannot apply {escape(chosen.label)}: "
                                f"{escape(str(exc))}</span>")
            return
        self.apply_requested.emit(pane)

    # -- model -> widgets -------------------------------------------------------------------------
    def refresh(self) -> None:
        """Show the document's advice: current, stale (greyed, not applicable), failed, or none yet."""
        doc, record = self.doc, self.doc.advice
        has_advice = record is not None and record.advice is not None
        current_failure = record is not None and record.advice is None and record.mesh_serial == doc.mesh_serial
        shown_label = escape(doc.source.label) if doc.source is not None else "no mesh"
        lines = []
        self.status.setToolTip("")
        if has_advice and doc.advice_current:
            lines.append(f"Advice for <b>{escape(record.source_label)}</b>")
            self.status.setToolTip(f"The advisor took {record.seconds:.2f} s on this mesh")
        elif has_advice:
            lines.append(f"<span style='color:{STALE_COLOUR}'><b>Stale:</b> this advice is for "
                         f"<b>{escape(record.source_label)}</b>, not for the mesh shown now "
                         f"(<b>{shown_label}</b>). Advise again for this mesh.</span>")
        elif current_failure:
            lines.append(f"<span style='color:{ERROR_COLOUR}'><b>No advice:</b> {escape(record.error)}</span>")
        elif doc.source is None:
            lines.append(f"<i>No mesh yet.</i> {INTRO}")
        else:
            lines.append(f"<i>No advice for {shown_label} yet.</i> {INTRO}")
        if self._running:
            lines.append(f"<i>Advising on {shown_label}…</i>")
        self.status.setText("<br>".join(lines))
        self._running_row.setVisible(self._running)

        self.why.setVisible(has_advice)
        self.check.setVisible(has_advice)
        self.features_box.setVisible(has_advice)
        self.ranking_box.setVisible(has_advice)
        if not has_advice:
            self._fill(None)
            self._update_apply()
            return
        if record is not self._shown_record:
            self._fill(record)
        current = doc.advice_current
        for w in (self.why, self.check, self.features_box, self.table):
            w.setEnabled(current)
        what = "point cloud" if record.advice.is_cloud else "mesh"
        self.features_box.setTitle(f"Measured on the {what}" if current else f"Measured on the earlier {what} (stale)")
        checked = record.advice.checked
        mesh_checked = checked and not record.advice.is_cloud  # the prediction and the realized error decide
        # a short title: a group box never wraps its title, and its width is the dock's minimum
        self.ranking_box.setTitle("Ranking by predicted × realized" if mesh_checked else
                                  "Ranking by measured error" if checked else "Ranking by predicted error")
        self.ranking_box.setToolTip(
            "Best first: the checked calls by the geometric mean of the table's predicted error and their error "
            "on the mesh itself against its smooth twin (realized), then the others" if mesh_checked else
            "Best first: the checked calls by the error measured on noisy copies of the input's smooth twin, then "
            "the others by the table's prediction" if checked else
            "Best first, by the error the study's table predicts for such an input")
        self._update_apply()

    def _fill(self, record) -> None:
        """Fill the summary, features and table from ``record`` (None: empty); select the recommendation."""
        self._shown_record = record
        self.table.setRowCount(0)
        self._rows = []
        if record is None:
            self.why.clear()
            for value in self.feature_values.values():
                value.clear()
            return
        advice = record.advice
        self.why.setText(advice.why)
        self.check.setText(check_text(advice))
        shown = set()
        for row in feature_rows(advice.features):
            self.feature_values[row.label].setText(row.text)
            self.feature_values[row.label].setToolTip(row.tooltip)
            self.feature_labels[row.label].setToolTip(row.tooltip)
            shown.add(row.label)
        for name, label in self.feature_labels.items():
            self._features_form.setRowVisible(label, name in shown)
        self._rows = ranking_rows(advice)
        self.table.setRowCount(len(self._rows))
        bold = QFont(self.font())
        bold.setBold(True)
        tint = QBrush(QColor(RECOMMENDED_BACKGROUND))
        for r, row in enumerate(self._rows):
            spec = ESTIMATORS.get(row.method)
            measured = row.measured_text + (" ≈" if row.within_noise else "")
            cells = {"Estimator": row.method, "Range": row.range_label, "Measured": measured,
                     "Valid": row.valid_text, "Predicted": row.erel_text, "Options": row.options_short}
            tips = dict(COLUMNS, Estimator=estimator_tooltip(spec) if spec is not None else row.method)
            for title, c in COLUMN.items():
                item = QTableWidgetItem(cells[title])
                item.setToolTip(("<b>Recommended</b><br>" if row.recommended else "") + f"<b>{escape(row.label)}</b><br>"
                                + tips[title])
                if title in ("Measured", "Valid", "Predicted"):
                    item.setTextAlignment(Qt.AlignmentFlag.AlignRight | Qt.AlignmentFlag.AlignVCenter)
                if row.recommended:
                    item.setFont(bold)
                    item.setBackground(tint)
                self.table.setItem(r, c, item)
            rank = QTableWidgetItem(f"{r + 1} ★" if row.recommended else str(r + 1))
            rank.setToolTip("Recommended" if row.recommended else f"Rank {r + 1}")
            if row.recommended:
                rank.setFont(bold)
            self.table.setVerticalHeaderItem(r, rank)
        self.table.selectRow(0)
        self.table.scrollToTop()

    def _update_apply(self) -> None:
        """Apply names the selected row and the active pane; it works only on current advice."""
        doc = self.doc
        letter = pane_letter(doc.active)
        usable = doc.advice_current and bool(self._rows)
        if usable:
            row = self._rows[self.selected_row()]
            self.apply_button.setText(f"Apply {row.label} to pane {letter}")
        else:
            self.apply_button.setText(f"Apply to pane {letter}")
        self.apply_button.setEnabled(usable)
        self.apply_button.setToolTip(
            f"Set pane {letter}'s estimator, range and options to the selected row (the recommendation unless "
            "you select another) and compute it; double-clicking a row does the same"
            if usable else "Advise on the mesh shown now first: this advice is for another mesh")
