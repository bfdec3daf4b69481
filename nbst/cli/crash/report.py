"""``nbst crash report CRASH.json -o report.html``: a reconstructionist's report of a crash file
(docs/crash.md, "Report"; the page is :mod:`nbst.render.crash.report`'s).

The file is read through the crash file's gate and the output checked (no link, FIFO, folder or
input file: nbst's output rules) before the replay; the page is written atomically.

Exit codes: 0 written, 2 bad input (one line, nothing written), 130 interrupted.
"""
from __future__ import annotations

import sys
from pathlib import Path

from nbst.errors import InputError
from nbst.outputs import prepare_output, sigterm_as_interrupt, write_text_atomic
from nbst.progress import seconds_text, since_start

__all__ = ["SUFFIXES", "cmd_report", "register_report"]

#: The names a report may have.
SUFFIXES = (".html", ".htm")


def register_report(cr) -> None:
    """Add ``report`` to the ``nbst crash`` subparsers ``cr``."""
    from nbst.cli.flags import add_quiet

    r = cr.add_parser("report", help="a reconstructionist's report of a crash file (HTML)",
                      description="Replay CRASH.json and write one self-contained HTML page: per vehicle its speed "
                                  "at impact, delta-V, PDOF (clock), EES when the file records crush and the "
                                  "intervals of a reconstruction when it carries one; every impact; the speed-time "
                                  "and sequence diagrams; the scene to scale; every fate or piece of evidence "
                                  "against the replay (asked, got, tolerance, met).",
                      epilog="Example: nbst crash report tbone.json -o tbone.html. Exit 0: written; 2: bad input "
                             "(nothing written).")
    r.add_argument("crash", metavar="CRASH.json", help="a crash file (nbst crash solve or reconstruct -o)")
    r.add_argument("-o", "--output", required=True, metavar="REPORT.html", help="where to write the page")
    add_quiet(r, "no summary line")
    r.set_defaults(func=cmd_report)


def cmd_report(args) -> int:
    """``nbst crash report CRASH.json -o REPORT.html [-q]``."""
    from nbst.models.crash import crashfile
    from nbst.render.crash.report import crash_report, report_html

    out = Path(args.output)
    if out.suffix.lower() not in SUFFIXES:
        raise InputError(f"-o {args.output}: the report is an HTML page; give a .html name")
    d, script, model = crashfile.load(args.crash)     # CrashFileError: one line naming the field
    prepare_output(out, inputs=(args.crash,))
    with sigterm_as_interrupt():
        rep = crash_report(d, script, model, source=str(args.crash))
        text = report_html(rep)
    write_text_atomic(out, text)
    if not args.quiet:
        k = len(rep.major())
        warn = "" if rep.motion.identical else f"; WARNING: {rep.motion.differs()}"
        print(f"nbst crash report: wrote {out} ({script.n} vehicles, {k} impact{'s' if k != 1 else ''}, "
              f"{len(text) / 1024:,.0f} KiB) in {seconds_text(since_start())}{warn}", file=sys.stderr)
    return 0
