#!/usr/bin/env bash
# Checks the documentation's links: every relative link and image in README.md, CONTRIBUTING.md, CHANGELOG.md and
# docs/*.md must point to an existing file or directory, and every #anchor into a
# Markdown file must name one of its headings (GitHub's heading slugs). Also checks that
# repository paths quoted in the text (scenarios/…, references/…, ci/…, docs/…,
# crates/…) exist. Needs python3. Run from anywhere: bash ci/check-links.sh
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v python3 >/dev/null 2>&1; then
    echo "check-links: python3 is needed" >&2
    exit 1
fi
python3 - README.md CONTRIBUTING.md CHANGELOG.md docs/*.md <<'EOF'
import os, re, sys

def strip_code_blocks(text):
    """Lines outside ``` fences, with their line numbers."""
    out, fenced = [], False
    for no, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("```"):
            fenced = not fenced
            continue
        if not fenced:
            out.append((no, line))
    return out

def slug(heading):
    """GitHub's anchor for a heading text."""
    h = re.sub(r"\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links → their text
    h = h.replace("`", "").strip().lower()
    h = re.sub(r"[^\w\- ]", "", h)
    return h.replace(" ", "-")

def anchors(path):
    seen, result = {}, set()
    for _, line in strip_code_blocks(open(path, encoding="utf-8").read()):
        m = re.match(r"^(#{1,6})\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        s = slug(m.group(2))
        n = seen.get(s, 0)
        result.add(s if n == 0 else f"{s}-{n}")
        seen[s] = n + 1
    return result

link = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)")
quoted_path = re.compile(r"(?<![\w./-])((?:scenarios|references|ci|docs|crates)/[\w./+-]*[\w/])")
errors = 0
for md in sys.argv[1:]:
    base = os.path.dirname(md)
    text = open(md, encoding="utf-8").read()
    for no, line in strip_code_blocks(text):
        for target in link.findall(re.sub(r"`[^`]*`", "", line)):
            if re.match(r"^[a-z]+:", target):
                continue  # http:, https:, mailto:
            path, _, anchor = target.partition("#")
            full = os.path.normpath(os.path.join(base, path)) if path else md
            if not os.path.exists(full):
                print(f"{md}:{no}: broken link {target} ({full} does not exist)")
                errors += 1
            elif anchor and full.endswith(".md") and anchor not in anchors(full):
                print(f"{md}:{no}: broken anchor {target} (no heading #{anchor} in {full})")
                errors += 1
    # Repository paths quoted anywhere, code blocks included.
    for no, line in enumerate(text.splitlines(), 1):
        for p in quoted_path.findall(line):
            if "<" in p or not os.path.exists(p.rstrip("/")):
                if "<" not in p:
                    print(f"{md}:{no}: path {p} does not exist")
                    errors += 1
if errors:
    print(f"check-links: {errors} problem(s)")
    sys.exit(1)
print(f"check-links: {len(sys.argv) - 1} files, all links and quoted paths resolve")
EOF
