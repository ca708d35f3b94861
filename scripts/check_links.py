#!/usr/bin/env python3
"""Every relative link in README.md and docs/**/*.md names a file that exists, and every
#anchor a heading of that file (GitHub's anchor rule). Run from the repository root."""
import pathlib
import re
import sys


def anchors(path):
    out = set()
    for line in path.read_text().split('\n'):
        m = re.match(r'^#+ (.*)', line)
        if m:
            out.add(re.sub(r'[^\w\- ]', '', m.group(1).strip().lower()).replace(' ', '-'))
    return out


def main():
    root = pathlib.Path('.')
    bad = 0
    for doc in [root / 'README.md'] + sorted((root / 'docs').rglob('*.md')):
        text = re.sub(r'```.*?```', '', doc.read_text(), flags=re.S)
        for m in re.finditer(r'\]\(([^)\s]+)\)', text):
            target = m.group(1)
            if re.match(r'^[a-z]+:', target):
                continue
            path, _, frag = target.partition('#')
            dest = doc.parent / path if path else doc
            if not dest.exists():
                print(f'{doc}: link to a missing file: {target}')
                bad += 1
            elif frag and dest.suffix == '.md' and frag not in anchors(dest):
                print(f'{doc}: link to a missing heading: {target}')
                bad += 1
    return 1 if bad else 0


if __name__ == '__main__':
    sys.exit(main())
