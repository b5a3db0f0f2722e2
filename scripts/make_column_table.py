"""Regenerate docs/guide/columns.md, the table of output columns in manual §4, from the column
registry (softtip.estimator.columns), and docs/guide/fused-columns.md, that of `softtip fuse` in
manual §8 (softtip.fusion.columns); tests/test_columns.py checks that they are current.

    python scripts/make_column_table.py
"""

from pathlib import Path

from softtip.estimator.columns import markdown_table
from softtip.fusion.fuse import fused_markdown_table

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide"


def main() -> None:
    for name, text in (("columns.md", markdown_table()), ("fused-columns.md", fused_markdown_table())):
        (GUIDE / name).write_text(text, encoding="utf-8")
        print(f"wrote {GUIDE / name}")


if __name__ == "__main__":
    main()
