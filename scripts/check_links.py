#!/usr/bin/python3
"""Checks that every relative link in README.md and docs/**/*.md resolves: the file exists and, for
a #fragment into a Markdown file, a heading with that GitHub anchor exists. Exit 1 on a broken link.
Usage: scripts/check_links.py   (from anywhere in the repository)"""
import os, re, sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")


def anchors(path):
    out, fence = set(), False
    for line in open(path, encoding="utf-8"):
        if line.startswith("```"):
            fence = not fence
        m = None if fence else re.match(r"#{1,6}\s+(.*?)\s*#*\s*$", line)
        if m:
            slug = re.sub(r"[^\w\- ]", "", m.group(1).strip().lower()).replace(" ", "-")
            n = 1
            base = slug
            while slug in out:
                slug = "%s-%d" % (base, n)
                n += 1
            out.add(slug)
    return out


def pages():
    yield os.path.join(ROOT, "README.md")
    for d, _, files in os.walk(os.path.join(ROOT, "docs")):
        for f in sorted(files):
            if f.endswith(".md"):
                yield os.path.join(d, f)


bad = 0
for page in pages():
    text, fence = [], False
    for line in open(page, encoding="utf-8"):
        if line.startswith("```"):
            fence = not fence
        text.append("" if fence else re.sub(r"`[^`]*`", "", line))  # not in code
    for n, line in enumerate(text, 1):
        for target in LINK.findall(line):
            if re.match(r"[a-z]+:", target):
                continue  # http:, https:, mailto:
            path, _, frag = target.partition("#")
            dest = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
            where = "%s:%d: %s" % (os.path.relpath(page, ROOT), n, target)
            if not dest.startswith(ROOT + os.sep):
                print(where + ": outside the repository"); bad += 1
            elif not os.path.exists(dest):
                print(where + ": no such file"); bad += 1
            elif frag and dest.endswith(".md") and frag not in anchors(dest):
                print(where + ": no such heading"); bad += 1
print("%d broken link(s)" % bad)
sys.exit(1 if bad else 0)
