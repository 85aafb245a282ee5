"""The README's commands for comparing experiments fit one screen (issue 45 Must 2): every ``dvc exp show``,
``dvc metrics diff`` and ``dvc params diff`` line of its shell blocks, run in this project as written, prints no line
over 120 characters in a terminal wide enough not to cut it, and shows every column it keeps."""

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
WIDTH = 120
COMMANDS = re.compile(r"^dvc (exp show|metrics diff|params diff)\b")


def readme_commands() -> list[list[str]]:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```sh\n(.*?)```", text, flags=re.S)
    return [shlex.split(line, comments=True) for block in blocks for line in block.splitlines() if COMMANDS.match(line)]


def test_the_readme_compares_experiments_in_commands_that_fit_120_characters():
    commands = readme_commands()
    assert {" ".join(c[:3]) for c in commands} >= {"dvc exp show", "dvc metrics diff", "dvc params diff"}, commands
    env = {**os.environ, "COLUMNS": "1000", "DVC_NO_ANALYTICS": "1", "PATH": f"{BIN}{os.pathsep}{os.environ['PATH']}"}
    for command in commands:
        args = [*command, "--no-pager"] if command[:3] == ["dvc", "exp", "show"] else command
        out = subprocess.run(args, cwd=ROOT, env=env, capture_output=True, text=True, timeout=300)
        assert out.returncode == 0, f"{shlex.join(command)}: {out.stderr[-2000:]}"
        widest = max((len(line.rstrip()) for line in out.stdout.splitlines()), default=0)
        assert widest <= WIDTH, f"{shlex.join(command)} prints lines of {widest} characters:\n{out.stdout}"
        if "--keep" in command:  # each kept column shown in full, none cut to "..."
            kept = command[command.index("--keep") + 1].strip("^$()").split("|")
            header = out.stdout.splitlines()[1].split()
            assert "…" not in out.stdout and set(kept) <= set(header), (kept, header)
