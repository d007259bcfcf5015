"""The one door for every change: each use case checks the right, makes the change and
journals it in one transaction of the archive (:mod:`stand.actions.door`).

The CLI, the station and the plant's servers call these and never write the journal
themselves; an :class:`Actor` says who (an account, or the operating system's user of a
lone stand) and from where.
"""

from stand.actions.accounts import add_account, lock_account, set_account
from stand.actions.calibration import save_calibration, save_matrix
from stand.actions.cycles import journal_abort
from stand.actions.door import Actor, Rights, os_actor, os_user
from stand.actions.evaluations import archive_evaluation
from stand.actions.jobs import command_job, leave_job, receive_job, start_job
from stand.actions.keys import trust_key
from stand.actions.release import release_certificate, signature_path
from stand.actions.rotor_types import config_seen, replace_config
from stand.actions.runs import archive_run, import_runs
from stand.actions.sessions import account_actor, log_in, log_in_badge, log_out, session_ended
from stand.actions.toolings import keep_tooling

__all__ = [
    "Actor",
    "Rights",
    "account_actor",
    "add_account",
    "archive_evaluation",
    "archive_run",
    "command_job",
    "config_seen",
    "import_runs",
    "journal_abort",
    "keep_tooling",
    "leave_job",
    "lock_account",
    "log_in",
    "log_in_badge",
    "log_out",
    "os_actor",
    "os_user",
    "receive_job",
    "release_certificate",
    "replace_config",
    "save_calibration",
    "save_matrix",
    "session_ended",
    "set_account",
    "signature_path",
    "start_job",
    "trust_key",
]
