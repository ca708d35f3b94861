//! Running a part program: lines lexed up front, O-word structure resolved per file,
//! then executed with a program counter through subroutine calls and control flow, with
//! the parameters (numbered, local and global named, predefined) each block reads.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::error::LineError;
use crate::expr::{parameter_index, Params};
use crate::interp::{Modal, ModalOp, State};
use crate::lexer::{lex_into, lex_line_into, Line, OKind, OWord, Target, Word};
use crate::persistent::{required_parameters, Parameters};
use crate::{Block, GcodeError, Options, Program};

/// Loop iterations (backward jumps) and subroutine calls a program may make in all
/// before it is refused as running away (`while` without end).
pub const MAX_ITERATIONS: u64 = 1_000_000;
/// Lines a program may execute beyond one pass over its files (lines that loops and
/// calls run again), so that no program interprets for long (about a second).
pub const MAX_REPEATED_LINES: u64 = 1_000_000;
/// Subroutine calls nest at most this deep: rs274 runs a call at `#<_call_level>` 9 and
/// refuses the next one ("Too many subroutine levels").
pub const MAX_CALL_DEPTH: usize = 9;
/// Subroutine parameters #1-#30 are saved around a call.
const SUB_PARAMS: usize = 30;

/// One line of a source file: its number, where its text stands, and, for a line with an
/// O-word, what it lexed to. Other lines are lexed when they are reached (so an error
/// is raised only then, as LinuxCNC reads lines only when it gets to them).
struct Entry {
    line: usize,
    text: std::ops::Range<usize>,
    lexed: Option<Box<Result<Line, LineError>>>,
}

/// Whether a line holds anything outside comments, and whether an `O` stands there.
fn scan(text: &str) -> (bool, bool) {
    let (mut content, mut o, mut comment) = (false, false, false);
    // Bytes will do: every character that matters here is ASCII.
    for &c in text.as_bytes() {
        match c {
            _ if comment => comment = c != b')',
            b'(' => comment = true,
            b';' => break,
            b' ' | b'\t' => {}
            b'o' | b'O' => (content, o) = (true, true),
            _ => content = true,
        }
    }
    (content, o)
}

/// Where an O-word line's partners stand (indices into the entries).
#[derive(Debug, Clone, Copy, Default)]
struct Links {
    /// if/elseif/else: the next elseif, else or endif.
    next_branch: Option<usize>,
    /// The structure's end: endif, endwhile, endrepeat, the closing while of a do, endsub.
    end: Option<usize>,
    /// The structure's start: while, do, repeat (for its end, break and continue).
    start: Option<usize>,
    /// A `while` that closes a `do`.
    closes_do: bool,
    /// An if, while, do or repeat whose label another such statement of the same
    /// subroutine (or of the main program) also uses: checked when it runs.
    shared_label: bool,
}

/// A lexed file with its O-word structure.
struct Source<'t> {
    name: String,
    text: std::borrow::Cow<'t, str>,
    entries: Vec<Entry>,
    links: Vec<Links>,
    /// A structure error found at an entry, raised if it is reached.
    broken: Vec<Option<String>>,
    /// Subroutines defined here: label to the entry of their `sub`.
    subs: HashMap<Box<str>, usize>,
}

fn oword(entry: &Entry) -> Option<&OWord> {
    entry.lexed.as_deref().and_then(|l| l.as_ref().ok()).and_then(|l| l.oword.as_ref())
}

impl<'t> Source<'t> {
    fn new(text: std::borrow::Cow<'t, str>, name: &str) -> Source<'t> {
        let mut entries = Vec::new();
        let mut seen_content = false;
        let (mut chars, mut columns) = (Vec::new(), Vec::new());
        let mut start = 0;
        for (index, raw) in text.split('\n').enumerate() {
            let range = start..start + raw.len();
            start += raw.len() + 1;
            let text = raw.strip_suffix('\r').unwrap_or(raw);
            let range = range.start..range.start + text.len();
            if text.trim_matches([' ', '\t']) == "%" {
                if seen_content {
                    break;
                }
                seen_content = true;
                continue;
            }
            let (content, o) = scan(text);
            if !content {
                continue;
            }
            seen_content = true;
            let lexed = o.then(|| Box::new(lex_line_into(text, &mut chars, &mut columns)));
            entries.push(Entry { line: index + 1, text: range, lexed });
        }
        let mut source = Source {
            name: name.to_string(),
            text,
            links: vec![Links::default(); entries.len()],
            broken: vec![None; entries.len()],
            entries,
            subs: HashMap::new(),
        };
        source.link();
        source
    }

    /// Matches every O-word structure by a stack over the file.
    fn link(&mut self) {
        // Open structures: (kind, label, entry, last branch entry).
        let mut open: Vec<(OKind, Box<str>, usize, usize)> = Vec::new();
        // The statements opening if, while, do and repeat, by (enclosing sub, label).
        let mut openers: HashMap<(Option<usize>, Box<str>), Vec<usize>> = HashMap::new();
        for i in 0..self.entries.len() {
            let Some(o) = oword(&self.entries[i]) else { continue };
            let (kind, label) = (o.kind, o.label.clone());
            let top_is = |open: &[(OKind, Box<str>, usize, usize)], kinds: &[OKind]| {
                open.last().is_some_and(|(k, l, _, _)| kinds.contains(k) && *l == label)
            };
            let fail = |s: &mut Source, message: String| s.broken[i] = Some(message);
            match kind {
                OKind::Sub => {
                    if open.iter().any(|(k, _, _, _)| *k == OKind::Sub) {
                        fail(self, format!("o{label} sub inside another subroutine's definition"));
                        continue;
                    }
                    self.subs.entry(label.clone()).or_insert(i);
                    open.push((kind, label, i, i));
                }
                OKind::If | OKind::While | OKind::Do | OKind::Repeat => {
                    if kind == OKind::While && top_is(&open, &[OKind::Do]) {
                        let (_, _, start, _) = open.pop().expect("do");
                        self.links[start].end = Some(i);
                        self.links[i].start = Some(start);
                        self.links[i].closes_do = true;
                        continue;
                    }
                    let sub = open.iter().find(|(k, _, _, _)| *k == OKind::Sub).map(|&(_, _, entry, _)| entry);
                    openers.entry((sub, label.clone())).or_default().push(i);
                    open.push((kind, label, i, i));
                }
                OKind::Elseif | OKind::Else => {
                    if !top_is(&open, &[OKind::If]) {
                        fail(self, format!("o{label} {kind:?} without a matching o{label} if").to_lowercase());
                        continue;
                    }
                    let top = open.last_mut().expect("if");
                    self.links[top.3].next_branch = Some(i);
                    top.3 = i;
                }
                OKind::Endif | OKind::Endwhile | OKind::Endrepeat | OKind::Endsub => {
                    let opener = match kind {
                        OKind::Endif => OKind::If,
                        OKind::Endwhile => OKind::While,
                        OKind::Endrepeat => OKind::Repeat,
                        _ => OKind::Sub,
                    };
                    if !top_is(&open, &[opener]) {
                        let what = format!("{kind:?}").to_lowercase();
                        fail(self, format!("o{label} {what} without a matching o{label} {:?}", opener).to_lowercase());
                        continue;
                    }
                    let (_, _, start, last) = open.pop().expect("opener");
                    self.links[last].next_branch = Some(i);
                    self.links[start].end = Some(i);
                    self.links[i].start = Some(start);
                    // Every branch of an if jumps to its endif at its end.
                    let mut b = start;
                    while let Some(next) = self.links[b].next_branch {
                        self.links[b].end = Some(i);
                        if next == i {
                            break;
                        }
                        b = next;
                    }
                }
                OKind::Break | OKind::Continue => {
                    let found = open
                        .iter()
                        .rev()
                        .take_while(|(k, _, _, _)| *k != OKind::Sub)
                        .find(|(k, l, _, _)| matches!(k, OKind::While | OKind::Do | OKind::Repeat) && *l == label);
                    match found {
                        // rs274: "no matching while/do label ... (found 'repeat' ...)".
                        Some(&(OKind::Repeat, _, _, _)) => {
                            let word = if kind == OKind::Break { "break" } else { "continue" };
                            fail(
                                self,
                                format!(
                                    "o{label} {word} inside o{label} repeat: LinuxCNC's break and continue serve \
                                     while and do loops only"
                                ),
                            )
                        }
                        Some(&(_, _, start, _)) => self.links[i].start = Some(start),
                        None => {
                            fail(self, format!("o{label} {kind:?} outside a loop labelled o{label}").to_lowercase())
                        }
                    }
                }
                OKind::Call | OKind::Return => {}
            }
        }
        for (kind, label, start, _) in open {
            self.broken[start] = Some(format!("o{label} {kind:?} is never closed").to_lowercase());
        }
        for entries in openers.values().filter(|e| e.len() > 1) {
            for &e in entries {
                self.links[e].shared_label = true;
            }
        }
    }
}

/// One subroutine call in progress (or the main program, at the bottom).
struct Frame {
    source: usize,
    pc: usize,
    /// The caller's #1-#30.
    params_saved: Option<[f64; SUB_PARAMS]>,
    /// Named parameters without a leading `_`.
    locals: HashMap<Box<str>, f64>,
    /// Remaining passes of the `repeat` loops open in this frame, by entry.
    repeats: HashMap<usize, u64>,
    /// The labels of the if, while, do and repeat statements run in this frame, with
    /// the entry that opened each: rs274 refuses a label used again by another
    /// statement in the same call ("duplicate O-word label").
    labels: HashMap<Box<str>, usize>,
    /// The modal state M70 saved at this level, and whether M73 saved it (restored on
    /// return).
    saved: Option<(Modal, bool)>,
}

/// The parameters a block reads: numbered ones from the state, named ones from the
/// frame and the globals, predefined ones from the state.
struct Scope<'a> {
    state: &'a State,
    locals: &'a HashMap<Box<str>, f64>,
    globals: &'a HashMap<Box<str>, f64>,
    /// Subroutine calls in progress (0 in the main program), for `#<_call_level>`.
    call_level: usize,
}

impl Scope<'_> {
    /// A global (`_`) parameter: set by the program, predefined, or one rs274 defines
    /// from the start (`#<_value>`, `#<_value_returned>`, `#<_call_level>`,
    /// `#<_remap_level>`). A global never set is not defined: reading it is an error, as
    /// in rs274 ("Named parameter #<_name> not defined").
    fn global(&self, name: &str) -> Option<f64> {
        self.globals.get(name).copied().or_else(|| self.state.predefined(name)).or(match name {
            "_value" | "_value_returned" | "_remap_level" => Some(0.0),
            "_call_level" => Some(self.call_level as f64),
            _ => None,
        })
    }
}

impl Params for Scope<'_> {
    fn numbered(&self, n: usize) -> f64 {
        self.state.parameter(n)
    }
    fn named(&self, name: &str) -> Option<f64> {
        if name.starts_with('_') {
            self.global(name)
        } else {
            self.locals.get(name).copied()
        }
    }
    fn exists(&self, name: &str) -> bool {
        if name.starts_with('_') {
            self.global(name).is_some()
        } else {
            self.locals.contains_key(name)
        }
    }
}

struct Runner<'o, 't> {
    sources: Vec<Source<'t>>,
    frames: Vec<Frame>,
    globals: HashMap<Box<str>, f64>,
    state: State,
    blocks: Vec<Block>,
    iterations: u64,
    /// Lines executed so far, and how many the files hold.
    executed: u64,
    lines_held: u64,
    options: &'o Options,
    /// The main program's folder, searched first for subroutine files.
    folder: Option<PathBuf>,
    /// Scratch space reused from line to line.
    line: Line,
    words: Vec<Word>,
    chars: Vec<char>,
    columns: Vec<usize>,
}

/// An error at an entry of a source.
fn located(source: &Source<'_>, entry: usize, e: LineError) -> GcodeError {
    GcodeError::Parse {
        file: source.name.clone(),
        line: source.entries.get(entry).map_or(0, |e| e.line),
        column: e.column,
        message: e.message,
    }
}

/// Runs a part program held in memory.
pub(crate) fn run(
    text: &str,
    file_name: &str,
    folder: Option<&Path>,
    options: &Options,
) -> Result<(Program, Parameters), GcodeError> {
    crate::persistent::check(&options.parameters.values)?;
    let main = Source::new(std::borrow::Cow::Borrowed(text), file_name);
    let mut runner = Runner {
        sources: vec![main],
        frames: vec![Frame {
            source: 0,
            pc: 0,
            params_saved: None,
            locals: HashMap::new(),
            repeats: HashMap::new(),
            labels: HashMap::new(),
            saved: None,
        }],
        globals: HashMap::new(),
        state: State::default(),
        blocks: Vec::new(),
        iterations: 0,
        executed: 0,
        lines_held: 0,
        options,
        folder: folder.map(Path::to_path_buf),
        line: Line::default(),
        words: Vec::new(),
        chars: Vec::new(),
        columns: Vec::new(),
    };
    runner.lines_held = runner.sources[0].entries.len() as u64;
    runner.state.set_tools(&options.tools);
    runner.state.set_machine_unit(options.machine_unit_mm);
    runner.state.load_parameters(&options.parameters.values);
    if runner.sources[0].entries.is_empty() {
        return Err(GcodeError::Parse {
            file: file_name.to_string(),
            line: 1,
            column: 1,
            message: "the program is empty (no blocks)".into(),
        });
    }
    runner.run()?;
    if let Some((line, column)) = runner.state.open_nurbs() {
        return Err(GcodeError::Parse {
            file: file_name.to_string(),
            line,
            column,
            message: "the program ends inside the NURBS block opened here (G5.3 missing)".into(),
        });
    }
    // The persistent parameters as the program leaves them: LinuxCNC's required ones
    // and every one the parameter file held.
    let values = required_parameters()
        .chain(options.parameters.values.keys().copied())
        .map(|n| (n, runner.state.parameter(n)))
        .collect();
    Ok((Program { blocks: runner.blocks }, Parameters { values }))
}

impl Runner<'_, '_> {
    fn run(&mut self) -> Result<(), GcodeError> {
        loop {
            let frame = self.frames.last().expect("a frame");
            let (s, pc) = (frame.source, frame.pc);
            let source = &self.sources[s];
            let Some(entry) = source.entries.get(pc) else {
                if self.frames.len() > 1 {
                    let at = source.entries.len().saturating_sub(1);
                    return Err(located(
                        source,
                        at,
                        LineError::new(1, "the file ends inside a subroutine (endsub missing)"),
                    ));
                }
                return Ok(());
            };
            let is_oword = match entry.lexed.as_deref() {
                Some(Ok(line)) => {
                    if let (Some(o), Some(message)) = (&line.oword, &source.broken[pc]) {
                        return Err(located(source, pc, LineError::new(o.column, message.clone())));
                    }
                    line.oword.is_some()
                }
                Some(Err(e)) => return Err(located(source, pc, e.clone())),
                None => false,
            };
            self.state.line = entry.line;
            self.executed += 1;
            if self.executed > self.lines_held + MAX_REPEATED_LINES {
                let column = entry
                    .lexed
                    .as_deref()
                    .and_then(|l| l.as_ref().ok())
                    .and_then(|l| l.oword.as_ref())
                    .map_or(1, |o| o.column);
                return Err(located(
                    source,
                    pc,
                    LineError::new(
                        column,
                        format!("execution limit reached: loops and calls ran {MAX_REPEATED_LINES} lines again (a loop that never ends?)"),
                    ),
                ));
            }
            let step = if is_oword { self.oword(s, pc) } else { self.block(s, pc) };
            match step {
                Ok(true) => {}
                Ok(false) => return Ok(()),
                Err(e) => return Err(located(&self.sources[s], pc, e)),
            }
        }
    }

    fn scope(&self) -> Scope<'_> {
        Scope {
            state: &self.state,
            locals: &self.frames.last().expect("frame").locals,
            globals: &self.globals,
            call_level: self.frames.len() - 1,
        }
    }

    fn count_iteration(&mut self, column: usize) -> Result<(), LineError> {
        self.iterations += 1;
        if self.iterations > MAX_ITERATIONS {
            return Err(LineError::new(
                column,
                format!(
                    "iteration limit reached: {MAX_ITERATIONS} loop passes and subroutine calls in all (a loop that never ends?)"
                ),
            ));
        }
        Ok(())
    }

    fn jump(&mut self, to: usize) {
        self.frames.last_mut().expect("frame").pc = to;
    }

    /// Executes an ordinary block; false when it ends the program.
    fn block(&mut self, s: usize, pc: usize) -> Result<bool, LineError> {
        let mut buffer = std::mem::take(&mut self.line);
        let mut words = std::mem::take(&mut self.words);
        words.clear();
        let entry = &self.sources[s].entries[pc];
        let line = match entry.lexed.as_deref() {
            Some(Ok(line)) => line,
            _ => {
                let text = &self.sources[s].text[entry.text.clone()];
                lex_into(text, &mut self.chars, &mut self.columns, &mut buffer)?;
                &buffer
            }
        };
        let scope = Scope {
            state: &self.state,
            locals: &self.frames.last().expect("frame").locals,
            globals: &self.globals,
            call_level: self.frames.len() - 1,
        };
        for w in &line.words {
            words.push(Word { letter: w.letter, value: w.value.eval(&scope)?, column: w.column });
        }
        let mut numbered: Vec<(usize, f64)> = Vec::new();
        let mut named: Vec<(Box<str>, f64)> = Vec::new();
        for a in &line.assigns {
            let value = a.value.eval(&scope)?;
            match &a.target {
                Target::Numbered(index) => {
                    let n = parameter_index(index.eval(&scope)?, a.column)?;
                    // LinuxCNC's read-only ones: the tool's (#5400-#5413) and the position's.
                    if matches!(n, 5400..=5413 | 5420..=5428) {
                        return Err(LineError::new(a.column, format!("#{n} is read-only")));
                    }
                    numbered.push((n, value))
                }
                Target::Named(name) => {
                    if self.state.predefined(name).is_some() {
                        return Err(LineError::new(a.column, format!("#<{name}> is read-only")));
                    }
                    named.push((name.clone(), value))
                }
            }
        }
        self.line = buffer;
        // Assignments take effect after the whole line is read, before it executes.
        for (n, value) in numbered {
            self.state.set_parameter(n, value);
        }
        for (name, value) in named {
            if name.starts_with('_') {
                self.globals.insert(name, value);
            } else {
                self.frames.last_mut().expect("frame").locals.insert(name, value);
            }
        }
        self.jump(pc + 1);
        if words.is_empty() {
            self.words = words;
            return Ok(true);
        }
        let executed = self.state.execute(&words);
        self.words = words;
        let executed = executed?;
        let line = self.state.line;
        self.blocks.extend(executed.kinds.into_iter().map(|kind| Block { line, n: executed.n, kind }));
        if let Some(op) = executed.modal {
            // M70/M73 save the state as the block leaves it; M72 restores at its end.
            let frame = self.frames.last_mut().expect("frame");
            match op {
                ModalOp::Save => frame.saved = Some((self.state.save_modal(), false)),
                ModalOp::SaveUntilReturn => frame.saved = Some((self.state.save_modal(), true)),
                ModalOp::Forget => frame.saved = None,
                ModalOp::Restore => {
                    let (modal, _) = frame
                        .saved
                        .ok_or_else(|| LineError::new(1, "M72 with no state saved by M70 at this call level"))?;
                    let kinds = self.state.restore_modal(&modal);
                    self.blocks.extend(kinds.into_iter().map(|kind| Block { line, n: executed.n, kind }));
                }
            }
        }
        Ok(!executed.end)
    }

    /// Executes an O-word line.
    fn oword(&mut self, s: usize, pc: usize) -> Result<bool, LineError> {
        let o = oword(&self.sources[s].entries[pc]).expect("oword").clone();
        let links = self.sources[s].links[pc];
        let column = o.column;
        let missing = |what: &str| LineError::new(column, format!("o{} {what} has no partner", o.label));
        let mut values = Vec::with_capacity(o.args.len());
        {
            let scope = self.scope();
            for a in &o.args {
                values.push(a.eval(&scope)?);
            }
        }
        let condition = values.first().is_some_and(|&v| v != 0.0);
        if links.shared_label {
            let frame = self.frames.last_mut().expect("frame");
            let first = match frame.labels.get(&o.label) {
                Some(&first) => first,
                None => *frame.labels.entry(o.label.clone()).or_insert(pc),
            };
            if first != pc {
                let line = self.sources[s].entries[first].line;
                return Err(LineError::new(
                    column,
                    format!(
                        "label o{} is already used on line {line}: LinuxCNC gives each if, while, do and repeat \
                         its own label within a subroutine (or the main program)",
                        o.label
                    ),
                ));
            }
        }
        match o.kind {
            OKind::Sub => self.jump(links.end.ok_or_else(|| missing("sub"))? + 1),
            OKind::Call => {
                self.jump(pc + 1);
                self.call(&o, &values)?;
            }
            OKind::Return | OKind::Endsub => {
                if self.frames.len() == 1 {
                    if o.kind == OKind::Endsub {
                        // Reached only by a jump into a definition; nothing to return from.
                        return Err(LineError::new(column, format!("o{} endsub outside a call", o.label)));
                    }
                    return Err(LineError::new(column, format!("o{} return outside a subroutine", o.label)));
                }
                let frame = self.frames.pop().expect("frame");
                if let Some(saved) = frame.params_saved {
                    for (i, v) in saved.iter().enumerate() {
                        self.state.set_parameter(i + 1, *v);
                    }
                }
                if let Some((modal, true)) = frame.saved {
                    let line = self.state.line;
                    let kinds = self.state.restore_modal(&modal);
                    self.blocks.extend(kinds.into_iter().map(|kind| Block { line, n: None, kind }));
                }
                match values.first() {
                    Some(&v) => {
                        self.globals.insert("_value".into(), v);
                        self.globals.insert("_value_returned".into(), 1.0);
                    }
                    None => {
                        // LinuxCNC: #<_value> is 0 after a return or endsub without one.
                        self.globals.insert("_value".into(), 0.0);
                        self.globals.insert("_value_returned".into(), 0.0);
                    }
                }
            }
            OKind::If => {
                let mut at = pc;
                let mut taken = condition;
                loop {
                    if taken {
                        self.jump(at + 1);
                        break;
                    }
                    let next = self.sources[s].links[at].next_branch.ok_or_else(|| missing("if"))?;
                    let entry = &self.sources[s].entries[next];
                    let branch = oword(entry).expect("branch");
                    match branch.kind {
                        OKind::Elseif => {
                            let cond = branch.args[0].clone();
                            let v = cond.eval(&self.scope()).map_err(|e| LineError::new(e.column, e.message))?;
                            at = next;
                            taken = v != 0.0;
                        }
                        OKind::Else => {
                            self.jump(next + 1);
                            break;
                        }
                        _ => {
                            self.jump(next + 1);
                            break;
                        }
                    }
                }
            }
            OKind::Elseif | OKind::Else => self.jump(links.end.ok_or_else(|| missing("elseif"))? + 1),
            OKind::Endif | OKind::Do => self.jump(pc + 1),
            OKind::While if links.closes_do => {
                if condition {
                    self.count_iteration(column)?;
                    self.jump(links.start.expect("do") + 1);
                } else {
                    self.jump(pc + 1);
                }
            }
            OKind::While => {
                if condition {
                    self.jump(pc + 1);
                } else {
                    self.jump(links.end.ok_or_else(|| missing("while"))? + 1);
                }
            }
            OKind::Endwhile => {
                self.count_iteration(column)?;
                self.jump(links.start.expect("while"));
            }
            OKind::Repeat => {
                let end = links.end.ok_or_else(|| missing("repeat"))?;
                let count = values[0].round();
                if count >= 1.0 {
                    self.frames.last_mut().expect("frame").repeats.insert(pc, count.min(u64::MAX as f64) as u64);
                    self.jump(pc + 1);
                } else {
                    self.jump(end + 1);
                }
            }
            OKind::Endrepeat => {
                let start = links.start.expect("repeat");
                let frame = self.frames.last_mut().expect("frame");
                let left = frame.repeats.get(&start).copied().unwrap_or(1).saturating_sub(1);
                if left > 0 {
                    frame.repeats.insert(start, left);
                    self.count_iteration(column)?;
                    self.jump(start + 1);
                } else {
                    frame.repeats.remove(&start);
                    self.jump(pc + 1);
                }
            }
            OKind::Break | OKind::Continue => {
                let start = links.start.expect("loop");
                let start_links = self.sources[s].links[start];
                let end = start_links.end.ok_or_else(|| missing("loop"))?;
                let start_kind = oword(&self.sources[s].entries[start]).expect("loop").kind;
                if o.kind == OKind::Break {
                    self.frames.last_mut().expect("frame").repeats.remove(&start);
                    self.jump(end + 1);
                } else {
                    // continue: the while re-tests; a do's closing while tests; a repeat counts down.
                    match start_kind {
                        OKind::While => {
                            self.count_iteration(column)?;
                            self.jump(start)
                        }
                        _ => self.jump(end),
                    }
                }
            }
        }
        Ok(true)
    }

    /// `oLABEL call [args]`: finds the subroutine (in a file of its own if need be) and
    /// enters it.
    fn call(&mut self, o: &OWord, args: &[f64]) -> Result<(), LineError> {
        self.count_iteration(o.column)?;
        if self.frames.len() > MAX_CALL_DEPTH {
            return Err(LineError::new(
                o.column,
                format!("subroutine calls nest more than {MAX_CALL_DEPTH} deep (LinuxCNC's limit: too many subroutine levels)"),
            ));
        }
        let current = self.frames.last().expect("frame").source;
        let found = std::iter::once(current)
            .chain(0..self.sources.len())
            .find_map(|s| self.sources[s].subs.get(&o.label).map(|&e| (s, e)));
        let (s, entry) = match found {
            Some(found) => found,
            None => self.load_sub_file(o)?,
        };
        if let Some(message) = &self.sources[s].broken[entry] {
            return Err(LineError::new(o.column, format!("o{} cannot be called: {message}", o.label)));
        }
        let mut saved = [0.0; SUB_PARAMS];
        for (i, v) in saved.iter_mut().enumerate() {
            *v = self.state.parameter(i + 1);
            self.state.set_parameter(i + 1, args.get(i).copied().unwrap_or(0.0));
        }
        self.frames.push(Frame {
            source: s,
            pc: entry + 1,
            params_saved: Some(saved),
            locals: HashMap::new(),
            repeats: HashMap::new(),
            labels: HashMap::new(),
            saved: None,
        });
        Ok(())
    }

    /// Loads `NAME.ngc` for `o<NAME> call` from the program's folder or the configured
    /// subroutine path.
    fn load_sub_file(&mut self, o: &OWord) -> Result<(usize, usize), LineError> {
        let not_found = || {
            LineError::new(
                o.column,
                format!("subroutine o{} is not defined here nor in a file of the subroutine path", o.label),
            )
        };
        let name = o.label.strip_prefix('<').and_then(|l| l.strip_suffix('>')).ok_or_else(not_found)?;
        let dirs = self.folder.iter().chain(self.options.subroutine_path.iter());
        let file = format!("{name}.ngc");
        for dir in dirs {
            let path = dir.join(&file);
            if let Ok(bytes) = std::fs::read(&path) {
                let text = String::from_utf8_lossy(&bytes).into_owned();
                let source = Source::new(std::borrow::Cow::Owned(text), &path.display().to_string());
                let entry = source.subs.get(&o.label).copied();
                self.lines_held += source.entries.len() as u64;
                self.sources.push(source);
                let s = self.sources.len() - 1;
                return entry.map(|e| (s, e)).ok_or_else(|| {
                    LineError::new(o.column, format!("{} does not define o{} sub", path.display(), o.label))
                });
            }
        }
        Err(not_found())
    }
}
