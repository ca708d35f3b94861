#!/usr/bin/env python3
"""Random differential check of finestep's G-code interpreter against LinuxCNC's rs274.

Generates random programs, runs each through `rs274 -g` and `finestep gcode-canon`,
and compares the traverse end points (X Y Z A, program units = mm here: no G20, no
offsets). Two kinds:

  expr    one `G0 X[...]` line after a few assignments: every operator and function,
          nesting, unary minus, numbered, local and global parameters, EXISTS
  oword   subroutines with arguments, recursion and return values, if/elseif/else,
          while, do-while, repeat, break/continue, same-line assignments, #5420, #<_x>

Usage: scripts/rs274_random.py expr|oword SEED COUNT [FINESTEP]
(FINESTEP defaults to target/release/finestep; `make conformance` installs rs274).
Prints agree / both refuse / disagree / one side refuses, and writes each program that
does not agree to build/rs274_random/. Results are in docs/gcode.md.
"""
import os
import random
import re
import subprocess
import sys

NUMBER = re.compile(r"-?\d+\.\d+")
OPS = ["**", "*", "/", "MOD", "+", "-", "EQ", "NE", "GT", "GE", "LT", "LE", "AND", "OR", "XOR"]
FUNCS = ["ABS", "ACOS", "ASIN", "COS", "EXP", "FIX", "FUP", "ROUND", "LN", "SIN", "SQRT", "TAN"]
VARS = ["#1", "#2", "#3", "#31", "#<a>", "#<_g>"]


def expr_number(rng):
    r = rng.random()
    if r < 0.3:
        return str(rng.randint(0, 9))
    if r < 0.6:
        return "%.3f" % rng.uniform(0, 10)
    if r < 0.7:
        return rng.choice(["0.5", "1.5", "2.5", "-2.5", "-0.5", "0.00005", "1.00005"])
    if r < 0.8:
        return rng.choice(["#1", "#2", "#3", "#<a>", "#<_g>"])
    return "-" + str(rng.randint(0, 5))


def expr_value(rng, depth):
    r = rng.random()
    if depth > 3 or r < 0.4:
        return expr_number(rng)
    if r < 0.6:
        return "[" + expression(rng, depth + 1) + "]"
    if r < 0.75:
        return rng.choice(FUNCS) + "[" + expression(rng, depth + 1) + "]"
    if r < 0.8:
        return "ATAN[" + expression(rng, depth + 1) + "]/[" + expression(rng, depth + 1) + "]"
    if r < 0.85:
        return "-" + expr_value(rng, depth + 1)
    if r < 0.9:
        return "EXISTS[#<" + rng.choice(["a", "b", "_g", "_h"]) + ">]"
    return expr_number(rng)


def expression(rng, depth):
    text = expr_value(rng, depth)
    for _ in range(rng.randint(0, 3)):
        text += " " + rng.choice(OPS) + " " + expr_value(rng, depth)
    return text


def expr_program(rng):
    text = expression(rng, 0)
    while len(text) > 200:  # rs274 refuses lines over 255 characters
        text = expression(rng, 0)
    return "#1=2.5 #2=-3 #3=0 #<a>=1.25 #<_g>=-0.75\nG0 X[" + text + "]\nM2\n"


class OwordGenerator:
    def __init__(self, rng):
        self.rng = rng
        self.label = 100

    def next_label(self):
        self.label += 1
        return self.label

    def value(self):
        rng = self.rng
        r = rng.random()
        if r < 0.4:
            return rng.choice(VARS)
        if r < 0.7:
            return str(rng.randint(-3, 5))
        op = rng.choice(["+", "-", "*", "MOD", "GT", "LT", "EQ", "AND", "OR"])
        return "[%s %s %s]" % (rng.choice(VARS), op, rng.randint(1, 4))

    def condition(self):
        op = self.rng.choice(["GT", "LT", "EQ", "NE", "GE", "LE"])
        return "[%s %s %s]" % (self.rng.choice(VARS), op, self.rng.randint(-2, 4))

    def block(self, depth, loop=None):
        out = []
        for _ in range(self.rng.randint(1, 3)):
            out += self.statement(depth, loop)
        return out

    def statement(self, depth, loop):
        rng = self.rng
        r = rng.random()
        if r < 0.25 or depth > 2:
            line = "%s = %s" % (rng.choice(VARS), self.value())
            if rng.random() < 0.5:
                line += " %s = %s" % (rng.choice(VARS), self.value())
            return [line]
        if r < 0.45:
            return ["G0 X%s Y%s" % (self.value(), self.value())]
        if r < 0.55:
            label = self.next_label()
            out = ["o%d if %s" % (label, self.condition())] + self.block(depth + 1, loop)
            for _ in range(rng.randint(0, 2)):
                out += ["o%d elseif %s" % (label, self.condition())] + self.block(depth + 1, loop)
            if rng.random() < 0.5:
                out += ["o%d else" % label] + self.block(depth + 1, loop)
            return out + ["o%d endif" % label]
        if r < 0.65:
            label = self.next_label()
            counter = "#<c%d>" % label
            return (
                ["%s = 0" % counter, "o%d while [%s LT %d]" % (label, counter, rng.randint(0, 4))]
                + ["%s = [%s + 1]" % (counter, counter)]
                + self.block(depth + 1, label)
                + ["o%d endwhile" % label]
            )
        if r < 0.72:
            label = self.next_label()
            counter = "#<c%d>" % label
            return (
                ["%s = 0" % counter, "o%d do" % label, "%s = [%s + 1]" % (counter, counter)]
                + self.block(depth + 1, label)
                + ["o%d while [%s LT %d]" % (label, counter, rng.randint(0, 3))]
            )
        if r < 0.8:
            # break and continue serve while and do loops only (rs274 refuses them in a
            # repeat); a repeat's body gets none.
            label = self.next_label()
            count = rng.choice(["0", "1", "2", "3", "#<_g>", "2.6"])
            return ["o%d repeat [%s]" % (label, count)] + self.block(depth + 1, None) + ["o%d endrepeat" % label]
        if r < 0.88 and loop:
            guard = self.next_label()
            word = rng.choice(["break", "continue"])
            return ["o%d if %s" % (guard, self.condition()), "o%d %s" % (loop, word), "o%d endif" % guard]
        if r < 0.95:
            call = "o<s%d> call [%s] [%s]" % (rng.randint(1, 2), self.value(), self.value())
            return [call, "G0 X#<_value> Y#1"]
        return ["G0 Z[#5420 + #5421] X#<_x>"]


SUBROUTINES = [
    "o<s1> sub",
    "#<loc> = [#1 * 2]",
    "G0 X#<loc> Y#2",
    "o901 if [#1 GT 1]",
    "o<s1> return [#1 + #2]",
    "o901 endif",
    "#<_g> = [#<_g> + 1]",
    "o<s1> endsub",
    "o<s2> sub",
    "#1 = [#1 + 10]",
    "G0 X#1 Y#2 Z#<_call_level>",
    "o902 if [#2 GT 0]",
    "o<s2> call [#2] [#2 - 1]",
    "o902 endif",
    "o<s2> endsub",
]


def oword_program(rng):
    generator = OwordGenerator(rng)
    body = ["#1=1 #2=2 #3=3 #31=0 #<a>=0 #<_g>=0 F100"] + generator.block(0) + generator.block(0) + ["M2"]
    return "\n".join(SUBROUTINES + body) + "\n"


def traverses(text, width):
    points = []
    for line in text.splitlines():
        if "TRAVERSE" in line:
            point = tuple(float(x) + 0.0 for x in NUMBER.findall(line)[:width])
            # finestep leaves out traverses that do not move.
            if not points or point != points[-1]:
                points.append(point)
    return [p for p in points if any(p)] if points else points


def main():
    kind, seed, count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    finestep = sys.argv[4] if len(sys.argv) > 4 else "target/release/finestep"
    rng = random.Random(seed)
    out = "build/rs274_random"
    os.makedirs(out, exist_ok=True)
    path = os.path.join(out, "program.ngc")
    tally = {"agree": 0, "both refuse": 0, "disagree": 0, "one side refuses": 0}
    for index in range(count):
        program = expr_program(rng) if kind == "expr" else oword_program(rng)
        with open(path, "w") as f:
            f.write(program)
        # A HOME of its own for rs274's $HOME/.tool.mmap (scripts/conformance.sh says why).
        theirs = subprocess.run(
            ["timeout", "10", "rs274", "-g", path], capture_output=True, text=True, stdin=subprocess.DEVNULL,
            env=dict(os.environ, HOME=out),
        )
        ours = subprocess.run(["timeout", "10", finestep, "gcode-canon", path], capture_output=True, text=True)
        if theirs.returncode or ours.returncode:
            outcome = "both refuse" if theirs.returncode and ours.returncode else "one side refuses"
        else:
            same = traverses(theirs.stdout, 4) == traverses(ours.stdout, 4)
            outcome = "agree" if same else "disagree"
        tally[outcome] += 1
        if outcome in ("disagree", "one side refuses"):
            name = os.path.join(out, "%s-%d-%d.ngc" % (kind, seed, index))
            with open(name, "w") as f:
                f.write(program)
            print("%s: %s" % (outcome, name))
    print("%s seed %d: %s" % (kind, seed, ", ".join("%s %d" % (k, v) for k, v in tally.items())))


if __name__ == "__main__":
    main()
