"""Whether a command's output shows what a document's `# shows:` promises.

usage: shows.py WANT < OUTPUT   (exit 0: a line of OUTPUT shows WANT)

WANT is read literally, except that a figure written `N±T` (for example
`2.05±0.01`) stands for any number within T of N, as a reader reads it. A
line shows WANT when WANT appears in it, its figures within their tolerance.
"""
import re
import sys

FIGURE = re.compile(r"(-?\d+(?:\.\d+)?)±(\d+(?:\.\d+)?)")
NUMBER = r"(-?\d+(?:\.\d+)?)"


def pattern(want):
    """A regex for WANT and the (value, tolerance) of each of its figures."""
    parts, figures, at = [], [], 0
    for m in FIGURE.finditer(want):
        parts.append(re.escape(want[at:m.start()]))
        parts.append(NUMBER)
        figures.append((float(m.group(1)), float(m.group(2))))
        at = m.end()
    parts.append(re.escape(want[at:]))
    return re.compile("".join(parts)), figures


def shows(want, lines):
    regex, figures = pattern(want)
    for line in lines:
        for m in regex.finditer(line):
            if all(abs(float(g) - v) <= t + 1e-12 for g, (v, t) in zip(m.groups(), figures)):
                return True
    return False


if __name__ == "__main__":
    if len(sys.argv) != 2:
        print(__doc__)
        sys.exit(2)
    sys.exit(0 if shows(sys.argv[1], sys.stdin.read().splitlines()) else 1)
