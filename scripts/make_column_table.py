"""Regenerate docs/guide/columns.md, the table of output columns in manual §4, from the column
registry (softtip.estimator.columns); tests/test_columns.py checks that it is current.

    python scripts/make_column_table.py
"""

from pathlib import Path

from softtip.estimator.columns import markdown_table

OUT = Path(__file__).resolve().parents[1] / "docs" / "guide" / "columns.md"


def main() -> None:
    OUT.write_text(markdown_table(), encoding="utf-8")
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
