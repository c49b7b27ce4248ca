"""The check report: its data model and its renderers (text, JSON)."""

from wavecheck.report.json import render_json, report_dict
from wavecheck.report.model import Report, overall_verdict
from wavecheck.report.text import render_text

__all__ = ["Report", "overall_verdict", "render_json", "render_text", "report_dict"]
