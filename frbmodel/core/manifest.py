"""What a command wrote into its output folder (``frb_manifest.json``), so that a re-run removes its own stale files.

A run that reuses an ``--out`` folder used to leave the earlier run's figures and tables beside its new ones (a
20 ... 30 krpm run-up next to composites up to 88 krpm). Now each command that makes a results folder *claims* it
(:func:`claim`) and writes a manifest with status ``running``. When it ends, :meth:`Claim.finish` deletes the files
the folder's previous manifest lists that this command did not write again — only those, and only if they are still
what that run wrote (same size and modification time), so a file a user added or edited is never touched — and lists
every file this command created or changed, with the final status (``finished``, ``stopped``, ``interrupted``,
``failed``). ``frb plot``, which re-draws a run's figures in its folder, adds its files to that run's manifest
(:func:`extend`). A command refused before it wrote anything puts the earlier manifest back and leaves the folder as it
was. A run killed outright (SIGKILL) leaves its ``running`` manifest, which still lists the earlier run's files (the
next run removes them) but not its own: what it wrote is not known, and stays.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

#: file name of the manifest in a results folder
MANIFEST = "frb_manifest.json"


def _signature(path):
    st = path.stat()
    return [st.st_size, st.st_mtime_ns]


def _files(folder):
    """Relative path -> [size, mtime_ns] of every file below ``folder`` except the manifest itself."""
    out = {}
    for root, _, names in os.walk(folder):
        for name in names:
            p = Path(root) / name
            rel = p.relative_to(folder).as_posix()
            if rel != MANIFEST and p.is_file():
                out[rel] = _signature(p)
    return out


def _read(folder):
    """The folder's manifest as a dict, or {} (none, or not one of ours)."""
    try:
        doc = json.loads((folder / MANIFEST).read_text())
    except (OSError, ValueError):
        return {}
    return doc if isinstance(doc, dict) else {}


def _listed(doc):
    """The files a manifest says its run wrote, and those of the run before it that it had not removed yet."""
    out = {}
    for key in ("previous_files", "files"):
        files = doc.get(key, {})
        out.update(files if isinstance(files, dict) else {})
    return out


def remove_stale(folder, files, keep=()) -> list:
    """Delete those of ``files`` (relative path -> [size, mtime_ns]) below ``folder`` that are unchanged since they
    were listed and not in ``keep``; the deleted relative paths. Subfolders emptied by it go too."""
    folder = Path(folder)
    gone = []
    for rel, sig in files.items():
        p = folder / rel
        try:
            if rel not in keep and p.is_file() and _signature(p) == list(sig):
                p.unlink()
                gone.append(rel)
        except OSError:
            continue
    for rel in sorted({str(Path(r).parent) for r in gone if Path(r).parent != Path(".")}, key=len, reverse=True):
        try:
            (folder / rel).rmdir()  # only if empty
        except OSError:
            pass
    return gone


@dataclass
class Claim:
    """A results folder claimed by one command: what was there before it started and what the last run wrote."""

    folder: Path
    command: str
    started_unix_s: float
    before: dict = field(repr=False, default_factory=dict)
    previous: dict = field(repr=False, default_factory=dict)
    previous_text: str | None = field(repr=False, default=None)
    removed: list = field(default_factory=list)
    #: an extension (``frb plot`` re-drawing a run's figures): the files it writes join the run's, nothing is removed
    extends: bool = False
    #: the outermost folder the command created for it (None: the folder was there): a refused command that wrote
    #: nothing removes the folders it made, as if it had not run
    created: Path | None = None

    def _write(self, status, files, previous=None):
        doc = {"command": self.command, "status": status, "started_unix_s": self.started_unix_s,
               "ended_unix_s": None if status == "running" else time.time(), "files": files}
        if previous:
            doc["previous_files"] = previous  # (still to remove if this run is killed)
        (self.folder / MANIFEST).write_text(json.dumps(doc, indent=1))

    def finish(self, status):
        """End the claim. ``refused`` (the command wrote nothing): the folder's earlier manifest is put back and its
        files kept. Otherwise the earlier run's files that this one did not write again and nobody changed are
        removed (:attr:`removed`), and the manifest lists every file this command created or changed."""
        if not self.folder.is_dir():
            return
        now = _files(self.folder)
        mine = {rel: sig for rel, sig in now.items() if self.before.get(rel) != sig}
        if self.extends:
            doc = _read(self.folder)
            if doc:  # (a folder without a manifest stays without one)
                doc["files"] = {**doc.get("files", {}), **mine}
                (self.folder / MANIFEST).write_text(json.dumps(doc, indent=1))
            return
        if status == "refused" and not mine:
            if self.previous_text is None:
                (self.folder / MANIFEST).unlink(missing_ok=True)
            else:
                (self.folder / MANIFEST).write_text(self.previous_text)
            self._remove_created()
            return
        self.removed = remove_stale(self.folder, self.previous, keep=mine)
        self._write(status, mine)


    def _remove_created(self):
        """Remove the folders this command created (:attr:`created` and those below it on the way to
        :attr:`folder`), where they are empty."""
        if self.created is None:
            return
        for root, dirs, _ in os.walk(self.folder, topdown=False):  # (empty subfolders it made, e.g. build/fmus)
            for d in dirs:
                try:
                    (Path(root) / d).rmdir()  # (only if empty)
                except OSError:
                    pass
        top, p = Path(self.created).resolve(), self.folder.resolve()
        chain = [p, *[q for q in p.parents if q == top or top in q.parents]]
        for q in chain:
            try:
                q.rmdir()  # (only if empty)
            except OSError:
                return


def extend(folder, command) -> Claim:
    """A claim that adds what ``command`` writes to the folder's manifest (when it ends) and removes nothing: for a
    command that writes into another run's results folder (``frb plot``)."""
    folder = Path(folder)
    return Claim(folder, command, time.time(), _files(folder) if folder.is_dir() else {}, extends=True)


def claim(folder, command, created=None) -> Claim:
    """Claim ``folder`` for ``command``: note what is there and what the last run listed, and write a manifest with
    status ``running`` (the stale files are removed when the command ends, :meth:`Claim.finish`); ``created`` is the
    outermost folder the command made for it (removed again if the command is refused before it writes anything)."""
    folder = Path(folder)
    try:
        text = (folder / MANIFEST).read_text()
    except OSError:
        text = None
    c = Claim(folder, command, time.time(), _files(folder), _listed(_read(folder)), text, created=created)
    c._write("running", {}, c.previous)
    return c


__all__ = ["MANIFEST", "Claim", "claim", "extend", "remove_stale"]
