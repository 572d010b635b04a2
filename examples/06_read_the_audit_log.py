"""Read the audit log: who did what, with which token, newest first, page by page.

    GCS_HUB=http://127.0.0.1:8000 GCS_TOKEN=... \\
        python examples/06_read_the_audit_log.py [--action command] [--actor NAME] [--last 50]

Needs the 'audit' permission (operators and admins; an API token needs the 'audit'
scope). Each entry names the credential used: an API token by its name, so an
integration's acts are told from its user's. The actions are listed in
docs/security.md; an unknown action or filter is refused naming the valid ones.
"""

import argparse
import datetime

from gcs_client import HubError, SyncHub

parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
parser.add_argument("--action", help="only this action (e.g. command, login, token.create)")
parser.add_argument("--actor", help="only this user (or agent:<vehicle>)")
parser.add_argument("--last", type=int, default=20, help="how many entries (default 20)")
parser.add_argument("--page", type=int, default=100, help="entries per request (up to 1000)")
args = parser.parse_args()

shown = 0
try:
    with SyncHub.from_env() as hub:
        # The client follows next_before_id from page to page (older entries each time).
        for entry in hub.audit.entries(
            action=args.action, actor=args.actor, last=args.last, page_size=args.page
        ):
            when = datetime.datetime.fromtimestamp(entry.time).isoformat(timespec="seconds")
            # The credential: an API token by its name, else how the actor logged in.
            credential = entry.token or entry.token_kind or "-"
            print(
                f"{entry.id:6} {when} {entry.actor:12} via {credential:12}"
                f" {entry.action:16} {entry.target:14} {entry.outcome}"
            )
            shown += 1
except HubError as error:
    raise SystemExit(f"error: {error}") from None
print(f"{shown} entries")
