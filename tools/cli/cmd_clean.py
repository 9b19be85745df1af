"""`silbridge clean`: list and remove shared-memory segments left by crashed runs.

A run that is SIGKILLed (or loses power) cannot unlink its segment; the file
/dev/shm/silbridge-<instance> then stays, holding memory. A segment is stale
when its owner no longer holds it (its lock is gone); live runs are listed and
never touched. Removal re-checks the owner under the lock (shm/leftovers.py).
"""

from __future__ import annotations

import json

HELP = "list and remove shared-memory segments left behind by crashed runs"


def add_arguments(p) -> None:
    p.add_argument("--dry-run", "--list", dest="dry_run", action="store_true",
                   help="only list segments (live and stale); remove nothing")
    p.add_argument("--match", default=None, metavar="GLOB",
                   help="only instance names matching GLOB, e.g. 'fly-*'")
    p.add_argument("--json", action="store_true", help="print one JSON object")


def run(args) -> int:
    from silbridge.shm.leftovers import list_segments, remove

    found = list_segments(args.match)
    removed, kept = [], []
    for s in found:
        if s.stale and not args.dry_run and remove(s.name):
            removed.append(s.name)
        elif s.stale and not args.dry_run:
            kept.append(s.name)     # came back to life / removed by someone else meanwhile
    rows = [{"name": s.name, "file": f"/dev/shm/silbridge-{s.name}", "owner_pid": s.owner_pid,
             "state": "live" if s.alive else ("removed" if s.name in removed else "stale"),
             "age_s": s.age_s, "bytes": s.bytes, "tag": s.tag} for s in found]
    stale = [r for r in rows if r["state"] != "live"]
    if args.json:
        print(json.dumps({"segments": rows, "stale": len(stale), "removed": removed,
                          "dry_run": args.dry_run}))
        return 0
    if not rows:
        print("no silbridge segments in /dev/shm")
        return 0
    for r in rows:
        age = "?" if r["age_s"] is None else f"{r['age_s']:.0f} s"
        tag = f"  tag {r['tag']}" if r["tag"] else ""
        print(f"{r['state']:<8} {r['file']:<48} owner pid {r['owner_pid']:<8} age {age:<8} "
              f"{r['bytes'] / 1e6:.1f} MB{tag}")
    if args.dry_run:
        print(f"{len(stale)} stale segment(s); run `silbridge clean` to remove them")
    else:
        print(f"removed {len(removed)} stale segment(s); live runs left alone")
    return 0
