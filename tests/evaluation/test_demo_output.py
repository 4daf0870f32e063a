"""What ``motionblur demo`` tells its user: the run names its report page, and the sheets and the
page say which reference each of an image's two RMSEs is measured against."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from motionblur.evaluation import demo, report


@pytest.mark.mitsuba
def test_the_demo_names_its_report_page_and_the_page_explains_the_two_rmses(tmp_path, capsys):
    assert demo.run(tmp_path / "demo", scenes="cube") == 0
    said = capsys.readouterr().out
    found = re.search(r"the report page [^:]*: (\S+index\.html)", said)
    assert found, said[-400:]
    page = Path(found.group(1))
    assert page.is_file() and page == tmp_path / "demo" / "html" / "index.html"
    text = page.read_text()
    assert "two RMSEs" in text and "against Mitsuba" in text and "own limit" in text
    assert (tmp_path / "demo" / "sheet_cube.png").is_file()


def test_a_sheet_label_names_the_reference_of_each_rmse():
    both = report._errors({"rmse": 0.0123, "rmse_limit": 0.0045})
    assert both == "RMSE 0.0123 Mitsuba / 0.0045 own"
    assert report._errors({"rmse": 0.0123}) == "RMSE 0.01230 Mitsuba"
