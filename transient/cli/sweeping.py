"""`transient sweep`: a campaign's command line, its rows printed, its exit code."""
import json
import os
import sys
from pathlib import Path


def cmd_sweep(args):
    from .. import api
    bars = []
    shown = not args.json and sys.stderr.isatty() and not os.environ.get("CI")

    def progress(done, total, failed):
        if shown and not bars:
            from tqdm import tqdm
            bars.append(tqdm(total=total, unit="variant", desc="sweep"))
        for bar in bars:
            bar.n = done
            bar.set_postfix(failed=failed)
            bar.refresh()

    campaign = api.sweep(args.case, args.param, args.out, args.mode or "grid", args.kind,
                         args.overrides, args.workers, args.scheduler, args.resume, progress,
                         None if args.json else lambda text: print(text, flush=True),
                         command=" ".join(["transient"] + args.argv), cache=args.cache)
    for bar in bars:
        bar.close()
    rows, variants, table = campaign.rows, campaign.variants, campaign.table
    if args.json:
        print(json.dumps({"rows": rows}))
    else:
        for row in rows:
            print(f"{row['variant']} {row['status']}"
                  + "".join(f" {k}={row[k]}" for k in variants[0].values))
        done = sum(r["status"] == "complete" for r in rows)
        print(f"{done} of {len(rows)} variants complete; wrote {table}, "
              f"{Path(args.out) / 'sweep.json'}")
    return _sweep_code(args, variants, rows, table)


def _sweep_code(args, variants, rows, table):
    """The exit code of a campaign from its rows, its first refused or unfinished variant
    said in one line: 2 if a variant was refused (bad input), else 3 if one did not complete
    (a run aborted, a task failed), else 0."""
    labels = {v.name: v.label() for v in variants}
    refused = [r for r in rows if r["status"].startswith("refused: ")]
    others = [r for r in rows if r["status"] != "complete" and r not in refused]
    if refused:
        r = refused[0]
        why = r.get("refusal") or {"file": args.case, "key": "", "message": r["status"]}
        print(f"error: {why['file']}: " + (f"{why['key']}: " if why["key"] else "")
              + f"variant {r['variant']} ({labels[r['variant']]}): {why['message']} "
              f"({len(refused)} of {len(rows)} variants refused; rows in {table})",
              file=sys.stderr)
        return 2
    if others:
        r = others[0]
        print(f"error: {len(others)} of {len(rows)} variants did not complete (variant "
              f"{r['variant']} ({labels[r['variant']]}): {r['status']}); rows in {table}",
              file=sys.stderr)
        return 3
    return 0
