"""bench/b_footprint.py derives deb-src entries from the system's apt sources, in both formats apt
reads: a fresh Debian 12 root made by mmdebstrap has only a one-line /etc/apt/sources.list, a cloud
image only deb822 /etc/apt/sources.list.d/debian.sources (the benchmark failed on the first)."""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

from b_footprint import deb_src_parts


def test_one_line_sources_list_as_mmdebstrap_writes_it(tmp_path: Path) -> None:
    (tmp_path / "sources.list").write_text(
        "# a comment: deb http://example.org/ bookworm main\n"
        "deb http://archive.invalid/debian bookworm main\n"
        "  deb [arch=amd64 signed-by=/k.gpg] http://archive.invalid/debian bookworm-updates main contrib\n"
        "deb-src http://archive.invalid/debian bookworm main\n")
    assert deb_src_parts(tmp_path) == {"src0.list": (
        "deb-src http://archive.invalid/debian bookworm main\n"
        "  deb-src [arch=amd64 signed-by=/k.gpg] http://archive.invalid/debian bookworm-updates main contrib\n")}


def test_deb822_sources_as_debian_12_cloud_images_write_them(tmp_path: Path) -> None:
    d = tmp_path / "sources.list.d"
    d.mkdir()
    (d / "debian.sources").write_text("Types: deb\nURIs: http://archive.invalid/debian\nSuites: bookworm\n"
                                      "Components: main\n\nTypes: deb deb-src\nURIs: http://x/\nSuites: y\n")
    (d / "notes.txt").write_text("deb http://ignored/ x main\n")
    assert deb_src_parts(tmp_path) == {"src0.sources": "Types: deb-src\nURIs: http://archive.invalid/debian\n"
                                       "Suites: bookworm\nComponents: main\n\nTypes: deb-src\nURIs: http://x/\n"
                                       "Suites: y\n"}


def test_both_formats_and_list_files_together(tmp_path: Path) -> None:
    d = tmp_path / "sources.list.d"
    d.mkdir()
    (tmp_path / "sources.list").write_text("deb http://a/ bookworm main\n")
    (d / "extra.list").write_text("deb http://b/ bookworm main\n")
    (d / "debian.sources").write_text("Types: deb\nURIs: http://c/\n")
    got = deb_src_parts(tmp_path)
    assert sorted(got.values()) == ["Types: deb-src\nURIs: http://c/\n", "deb-src http://a/ bookworm main\n",
                                    "deb-src http://b/ bookworm main\n"]


def test_no_archive_anywhere_is_empty(tmp_path: Path) -> None:
    (tmp_path / "sources.list").write_text("# nothing here\n")
    assert deb_src_parts(tmp_path) == {}
