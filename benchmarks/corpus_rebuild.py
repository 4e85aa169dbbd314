"""Rebuild the benchmark corpus (the manifest's root = "corpus" recordings) from git mirrors:
``python3 benchmarks/corpus_rebuild.py [--corpus /work/corpus_data] [--mirrors /work/.mirror] [--only NAME]``.

Each recording's ``[recording.source]`` in benchmarks/real_corpus.toml names a GitHub repository,
a commit (the ones its ``origin`` names: checked) and the files: a local path inside the
recording's folder (the first part of its ``path``) = the path at that commit, a trailing ``/``
copying a folder (``leave_out``: the local paths below it not copied). The files are written from the
mirror's objects byte for byte (``git cat-file blob``); then ``derive = [script, name]`` is copied
beside the data under that name and run there (``python3 NAME FOLDER``). Every file written is
listed in CORPUS/REBUILT.tsv with the commit and blob it came from.

The mirrors are bare clones at MIRRORS/OWNER+NAME/repo (what the session's ``fetch`` tool makes);
this script does not fetch: when one is missing it prints the ``fetch`` sources it needs
(``github:OWNER/NAME``) and stops. When a mirror lacks the named commit, each file is taken from
the newest commit of the mirror that holds its path; the choice is printed with the commit passed
over, and REBUILT.tsv names the commit used (check the content against docs/real_corpus.md).
"""
from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
MANIFEST = ROOT / "benchmarks" / "real_corpus.toml"


class RebuildError(Exception):
    """A manifest entry or a mirror that cannot give the files (the message names which)."""


def git(mirror: Path, *args: str, binary: bool = False):
    done = subprocess.run(["git", f"--git-dir={mirror}", *args], capture_output=True)
    if done.returncode:
        raise RebuildError(f"{mirror}: git {' '.join(args)}: {done.stderr.decode(errors='replace').strip()}")
    return done.stdout if binary else done.stdout.decode()


def corpus_recordings(manifest: Path, only: list[str]) -> list[dict]:
    """The root = "corpus" recordings (those named in ``only`` if given), each with a checked source."""
    recs = [r for r in tomllib.loads(manifest.read_text())["recording"] if r.get("root") == "corpus"]
    unknown = set(only) - {r["name"] for r in recs}
    if unknown:
        raise RebuildError(f"{manifest}: --only {sorted(unknown)}: no root = \"corpus\" recording of that name")
    recs = [r for r in recs if not only or r["name"] in only]
    for r in recs:
        src = r.get("source")
        where = f"{manifest}: recording {r['name']!r}"
        if not isinstance(src, dict) or not {"repo", "commit", "files"} <= set(src):
            raise RebuildError(f"{where}: [recording.source] needs repo, commit and files")
        if src["repo"] not in r.get("origin", "") or src["commit"] not in r.get("origin", ""):
            raise RebuildError(f"{where}: source repo {src['repo']} @ {src['commit']} is not the one its origin "
                               f"names ({r.get('origin')!r})")
    return recs


def mirror_of(repo: str, mirrors: Path) -> Path:
    return mirrors / repo.replace("/", "+") / "repo"


def commit_for(mirror: Path, commit: str, path: str) -> tuple[str, str]:
    """(the commit to read ``path`` at, a note): the named one, else the mirror's newest holding it."""
    try:
        git(mirror, "cat-file", "-e", f"{commit}^{{commit}}")
        return commit, ""
    except RebuildError:
        pass
    newest = git(mirror, "log", "--all", "-1", "--format=%H", "--", path.rstrip("/")).strip()
    if not newest:
        raise RebuildError(f"{mirror}: commit {commit} absent and no commit holds {path!r}")
    return newest, f"commit {commit} absent from the mirror: {path} taken from {newest} (its newest commit holding it)"


def blobs(mirror: Path, commit: str, upstream: str) -> list[tuple[str, str]]:
    """(path relative to ``upstream``, blob id) of the file, or of every file below a folder ``upstream/``."""
    out = []
    for line in git(mirror, "ls-tree", "-r", "-z", commit, "--", upstream.rstrip("/")).split("\0"):
        if not line:
            continue
        meta, path = line.split("\t", 1)
        kind, sha = meta.split()[1:3]
        rel = path[len(upstream):] if upstream.endswith("/") else ""
        if kind == "blob":
            out.append((rel, sha))
    if not out:
        raise RebuildError(f"{mirror}: no file {upstream!r} at {commit}")
    return out


def extract(rec: dict, corpus: Path, mirrors: Path) -> list[str]:
    """Write the recording's files into its folder; the REBUILT.tsv lines for them."""
    src = rec["source"]
    mirror, folder = mirror_of(src["repo"], mirrors), corpus / Path(rec["path"]).parts[0]
    lines = []
    for local, upstream in src["files"].items():
        commit, note = commit_for(mirror, src["commit"], upstream)
        if note:
            print(f"  {rec['name']}: {note}")
        for rel, sha in blobs(mirror, commit, upstream):
            if any(str(Path(local) / rel).startswith(x.rstrip("/")) for x in src.get("leave_out", [])):
                continue
            target = (folder / local / rel) if upstream.endswith("/") else folder / local
            target.parent.mkdir(parents=True, exist_ok=True)
            try:
                target.write_bytes(git(mirror, "cat-file", "blob", sha, binary=True))
            except RebuildError as e:
                raise RebuildError(f"{rec['name']}: {upstream}{rel} ({sha}) is not in the mirror's objects (a "
                                   f"snapshot that left out its largest files?): {e}") from None
            lines.append(f"{target.relative_to(corpus)}\t{src['repo']}\t{commit}\t{upstream}{rel}\t{sha}")
    return lines


def derive(rec: dict, corpus: Path) -> None:
    """Copy the derive script beside the data under its name and run it on the folder."""
    script, name = rec["source"]["derive"]
    folder = corpus / Path(rec["path"]).parts[0]
    shutil.copyfile(ROOT / script, folder / name)
    done = subprocess.run([sys.executable, str(folder / name), str(folder)], capture_output=True, text=True)
    if done.returncode:
        raise RebuildError(f"{rec['name']}: {folder / name} failed: {done.stderr.strip()}")
    print("  " + done.stdout.strip().replace("\n", "\n  "))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--manifest", type=Path, default=MANIFEST)
    ap.add_argument("--corpus", type=Path, default=Path("/work/corpus_data"))
    ap.add_argument("--mirrors", type=Path, default=Path("/work/.mirror"))
    ap.add_argument("--only", action="append", default=[], help="a recording's name (repeatable)")
    a = ap.parse_args()
    try:
        recs = corpus_recordings(a.manifest, a.only)
        missing = sorted({r["source"]["repo"] for r in recs if not mirror_of(r["source"]["repo"], a.mirrors).is_dir()})
        if missing:
            print(f"missing mirrors under {a.mirrors}; fetch these sources, then run again:")
            print("\n".join(f"  github:{repo}" for repo in missing))
            return 2
        lines = []
        for rec in recs:
            print(f"{rec['name']}: {rec['source']['repo']} @ {rec['source']['commit'][:7]}")
            lines += extract(rec, a.corpus, a.mirrors)
            if "derive" in rec["source"]:
                derive(rec, a.corpus)
            if not (a.corpus / rec["path"]).exists():
                raise RebuildError(f"{rec['name']}: path {rec['path']} not among the files its source gave")
    except RebuildError as e:
        print(f"corpus_rebuild: {e}", file=sys.stderr)
        return 1
    record = a.corpus / "REBUILT.tsv"
    kept = [ln for ln in (record.read_text().splitlines()[1:] if record.exists() else [])
            if ln.split("\t")[0] not in {x.split("\t")[0] for x in lines}]
    record.write_text("\n".join(["local\trepo\tcommit\tupstream path\tblob", *sorted(kept + lines)]) + "\n")
    print(f"{len(lines)} files from {len(recs)} recordings into {a.corpus} (listed in {record})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
