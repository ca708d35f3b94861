//! Running a part program: executed with a program counter (a byte offset and line
//! number) through subroutine calls and control flow, each line read and lexed when it
//! is reached, with the parameters (numbered, local and global named, predefined) each
//! block reads. The O-word structure of each file is matched by a scan that runs ahead
//! of execution only as far as execution needs it, so that a program is executed (and
//! its blocks handed on) as it is read: neither its text nor its blocks are held whole.

use std::collections::{HashMap, VecDeque};
use std::fs::File;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};

use crate::error::LineError;
use crate::expr::{parameter_index, Params};
use crate::g7x::{cycle_moves, LatheCycle, ProfileReader};
use crate::interp::{Modal, ModalOp, State, PARAM_DEBUG};
use crate::lexer::scan;
use crate::lexer::{lex_into, lex_line_into, Line, OKind, OWord, Target, Word};
use crate::message::{expand, Active, LexedMessage};
use crate::persistent::{required_parameters, Parameters};
use crate::{Block, BlockKind, GcodeError, MessageKind, Options};

/// Loop iterations (backward jumps) and subroutine calls a program may make in all
/// before it is refused as running away (`while` without end).
pub const MAX_ITERATIONS: u64 = 1_000_000;
/// Lines a program may execute beyond one pass over its files (lines that loops and
/// calls run again), so that no program interprets for long (about a second).
pub const MAX_REPEATED_LINES: u64 = 1_000_000;
/// How far the structure scan reads ahead of execution, bytes: a small program is
/// scanned whole at its first line (its labels' sharing then known, so loops need not
/// keep them), a long one a bounded stretch at a time.
const SCAN_AHEAD_BYTES: usize = 64 * 1024;
/// Subroutine calls nest at most this deep: rs274 runs a call at `#<_call_level>` 9 and
/// refuses the next one ("Too many subroutine levels").
pub const MAX_CALL_DEPTH: usize = 9;
/// Subroutine parameters #1-#30 are saved around a call.
const SUB_PARAMS: usize = 30;

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

/// A line of a source file with an `O` outside comments (an O-word, or a function such
/// as COS or MOD) that lexes: its number, where it stands (byte offsets of its start and
/// of the line after it) and what it lexed to, so that loops do not lex it again. Other
/// lines are not kept: they are read and lexed when they are reached (so an error is
/// raised only then, as LinuxCNC reads lines only when it gets to them).
struct Entry {
    line: usize,
    offset: usize,
    next: usize,
    lexed: Line,
}

/// Where execution stands in a file: the byte offset of a line and its 1-based number.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Pc {
    offset: usize,
    line: usize,
}

/// Reads a file's lines from a byte offset: from memory, or from the file itself through
/// a buffer (moved by a relative seek, so a loop's jump back within the buffer reads
/// nothing again), so that a program file is never held whole.
enum Reader {
    Memory,
    File { file: BufReader<File>, pos: usize, bytes: Vec<u8> },
}

impl Reader {
    fn open(path: &Path) -> std::io::Result<Reader> {
        Ok(Reader::File { file: BufReader::with_capacity(64 * 1024, File::open(path)?), pos: 0, bytes: Vec::new() })
    }

    /// The line starting at `offset` into `out` (without its `\n` and a `\r` before it),
    /// and the offset of the line after it; `None` at the end of the text.
    fn read(&mut self, memory: &str, offset: usize, out: &mut String) -> std::io::Result<Option<usize>> {
        out.clear();
        let next = match self {
            Reader::Memory => {
                let Some(rest) = memory.get(offset..).filter(|r| !r.is_empty()) else { return Ok(None) };
                let (line, next) = match rest.find('\n') {
                    Some(end) => (&rest[..end], offset + end + 1),
                    None => (rest, memory.len() + 1),
                };
                out.push_str(line);
                next
            }
            Reader::File { file, pos, bytes } => {
                if offset != *pos {
                    file.seek_relative(offset as i64 - *pos as i64)?;
                    *pos = offset;
                }
                bytes.clear();
                let n = file.read_until(b'\n', bytes)?;
                if n == 0 {
                    return Ok(None);
                }
                *pos += n;
                if bytes.last() == Some(&b'\n') {
                    bytes.pop();
                }
                // Line by line as for the whole text: a `\n` ends any sequence that is
                // not UTF-8, so each is replaced the same way.
                out.push_str(&String::from_utf8_lossy(bytes));
                offset + n
            }
        };
        if out.ends_with('\r') {
            out.pop();
        }
        Ok(Some(next))
    }
}

/// A source file: its text read as execution reaches it, and its O-word structure
/// matched by a scan that runs ahead of execution only as far as execution needs (at
/// least past the line being run; to a structure's end when it is entered; to the end of
/// the file for a subroutine it does not define so far).
struct Source<'t> {
    name: String,
    memory: std::borrow::Cow<'t, str>,
    /// Execution's reader, and the scan's.
    reader: Reader,
    scan_reader: Reader,
    /// The scan: the next line's offset and number, the line buffer and lexer scratch.
    scan_at: Pc,
    scan_line: String,
    chars: Vec<char>,
    columns: Vec<usize>,
    /// The scan has met a line with content, reached the end, the closing `%` at this offset.
    seen_content: bool,
    complete: bool,
    end_offset: Option<usize>,
    /// Lines with content scanned, and the last one's number.
    content_lines: u64,
    last_content_line: usize,
    /// A read error met by the scan (raised by execution at its next line).
    failed: Option<std::io::Error>,
    entries: Vec<Entry>,
    links: Vec<Links>,
    /// A structure error found at an entry, raised if it is reached.
    broken: Vec<Option<String>>,
    /// Subroutines defined here: label to the entry of their `sub`.
    subs: HashMap<Box<str>, usize>,
    /// Structures open at the scan: (kind, label, entry, last branch entry).
    open: Vec<(OKind, Box<str>, usize, usize)>,
    /// The statements opening if, while, do and repeat, by (enclosing sub, label).
    openers: HashMap<(Option<usize>, Box<str>), Vec<usize>>,
}

fn oword(entry: &Entry) -> &OWord {
    entry.lexed.oword.as_ref().expect("an O-word line")
}

impl<'t> Source<'t> {
    fn new(memory: std::borrow::Cow<'t, str>, reader: Reader, scan_reader: Reader, name: &str) -> Source<'t> {
        Source {
            name: name.to_string(),
            memory,
            reader,
            scan_reader,
            scan_at: Pc { offset: 0, line: 1 },
            scan_line: String::new(),
            chars: Vec::new(),
            columns: Vec::new(),
            seen_content: false,
            complete: false,
            end_offset: None,
            content_lines: 0,
            last_content_line: 0,
            failed: None,
            entries: Vec::new(),
            links: Vec::new(),
            broken: Vec::new(),
            subs: HashMap::new(),
            open: Vec::new(),
            openers: HashMap::new(),
        }
    }

    fn in_memory(text: std::borrow::Cow<'t, str>, name: &str) -> Source<'t> {
        Source::new(text, Reader::Memory, Reader::Memory, name)
    }

    /// The entry of the O-word line at `offset`, if it is one.
    fn entry_at(&self, offset: usize) -> Option<usize> {
        self.entries.binary_search_by_key(&offset, |e| e.offset).ok()
    }

    /// Scans one more line; false once the scan is complete.
    fn scan_one(&mut self) -> bool {
        if self.complete {
            return false;
        }
        let at = self.scan_at;
        let next = match self.scan_reader.read(&self.memory, at.offset, &mut self.scan_line) {
            Ok(Some(next)) => next,
            Ok(None) => {
                self.finish_scan();
                return false;
            }
            Err(e) => {
                self.failed = Some(e);
                self.finish_scan();
                return false;
            }
        };
        self.scan_at = Pc { offset: next, line: at.line + 1 };
        let text = self.scan_line.as_str();
        if text.trim_matches([' ', '\t']) == "%" {
            if self.seen_content {
                self.end_offset = Some(at.offset);
                self.finish_scan();
                return false;
            }
            self.seen_content = true;
            return true;
        }
        let (content, o) = scan(text);
        if !content {
            return true;
        }
        self.seen_content = true;
        self.content_lines += 1;
        self.last_content_line = at.line;
        if o {
            if let Ok(lexed) = lex_line_into(text, &mut self.chars, &mut self.columns) {
                let is_oword = lexed.oword.is_some();
                self.entries.push(Entry { line: at.line, offset: at.offset, next, lexed });
                self.links.push(Links::default());
                self.broken.push(None);
                if is_oword {
                    self.link(self.entries.len() - 1);
                }
            }
        }
        true
    }

    /// Scans past the line at `offset` and [`SCAN_AHEAD_BYTES`] beyond (or to the end).
    fn scan_past(&mut self, offset: usize) {
        if self.scan_at.offset <= offset {
            while self.scan_at.offset <= offset + SCAN_AHEAD_BYTES && self.scan_one() {}
        }
    }

    /// Scans until entry `i`'s structure is closed (or to the end).
    fn settle(&mut self, i: usize) {
        while self.links[i].end.is_none() && !self.links[i].closes_do && self.scan_one() {}
    }

    /// Scans to the end.
    fn scan_all(&mut self) {
        while self.scan_one() {}
    }

    /// Subroutine `label` defined here: the first definition (scanning to the end for one
    /// not met so far).
    fn sub(&mut self, label: &str) -> Option<usize> {
        if let Some(&entry) = self.subs.get(label) {
            return Some(entry);
        }
        self.scan_all();
        self.subs.get(label).copied()
    }

    /// The end of the file: what is still open is never closed; labels shared between
    /// statements are marked.
    fn finish_scan(&mut self) {
        self.complete = true;
        for (kind, label, start, _) in std::mem::take(&mut self.open) {
            self.broken[start] = Some(format!("o{label} {kind:?} is never closed").to_lowercase());
        }
        for entries in self.openers.values().filter(|e| e.len() > 1) {
            for &e in entries {
                self.links[e].shared_label = true;
            }
        }
    }

    /// Matches O-word entry `i` into the structures open (a stack over the file).
    fn link(&mut self, i: usize) {
        let o = oword(&self.entries[i]);
        let (kind, label) = (o.kind, o.label.clone());
        let top_is = |open: &[(OKind, Box<str>, usize, usize)], kinds: &[OKind]| {
            open.last().is_some_and(|(k, l, _, _)| kinds.contains(k) && *l == label)
        };
        let fail = |s: &mut Source, message: String| s.broken[i] = Some(message);
        match kind {
            OKind::Sub => {
                if self.open.iter().any(|(k, _, _, _)| *k == OKind::Sub) {
                    fail(self, format!("o{label} sub inside another subroutine's definition"));
                    return;
                }
                self.subs.entry(label.clone()).or_insert(i);
                self.open.push((kind, label, i, i));
            }
            OKind::If | OKind::While | OKind::Do | OKind::Repeat => {
                if kind == OKind::While && top_is(&self.open, &[OKind::Do]) {
                    let (_, _, start, _) = self.open.pop().expect("do");
                    self.links[start].end = Some(i);
                    self.links[i].start = Some(start);
                    self.links[i].closes_do = true;
                    return;
                }
                let sub = self.open.iter().find(|(k, _, _, _)| *k == OKind::Sub).map(|&(_, _, entry, _)| entry);
                self.openers.entry((sub, label.clone())).or_default().push(i);
                self.open.push((kind, label, i, i));
            }
            OKind::Elseif | OKind::Else => {
                if !top_is(&self.open, &[OKind::If]) {
                    fail(self, format!("o{label} {kind:?} without a matching o{label} if").to_lowercase());
                    return;
                }
                let top = self.open.last_mut().expect("if");
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
                if !top_is(&self.open, &[opener]) {
                    let what = format!("{kind:?}").to_lowercase();
                    fail(self, format!("o{label} {what} without a matching o{label} {:?}", opener).to_lowercase());
                    return;
                }
                let (_, _, start, last) = self.open.pop().expect("opener");
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
                let found = self
                    .open
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
                    None => fail(self, format!("o{label} {kind:?} outside a loop labelled o{label}").to_lowercase()),
                }
            }
            OKind::Call | OKind::Return => {}
        }
    }

    /// Where execution goes to run entry `i` itself, and to run the line after it.
    fn at_entry(&self, i: usize) -> Pc {
        Pc { offset: self.entries[i].offset, line: self.entries[i].line }
    }
    fn after_entry(&self, i: usize) -> Pc {
        Pc { offset: self.entries[i].next, line: self.entries[i].line + 1 }
    }
}

/// One subroutine call in progress (or the main program, at the bottom).
struct Frame {
    source: usize,
    pc: Pc,
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

/// A lathe cycle whose profile is being read from its Q subroutine.
struct LatheRead {
    cycle: LatheCycle,
    reader: ProfileReader,
    /// The number of frames when the cycle's line ran: the profile is read until the
    /// subroutine returns to it.
    frames: usize,
    /// Where the cycle's line is: source, line, N word.
    source: usize,
    line: usize,
    n: Option<u32>,
}

/// A part program executed as its blocks are asked for ([`crate::BlockStream`]).
pub(crate) struct Runner<'t> {
    sources: Vec<Source<'t>>,
    frames: Vec<Frame>,
    globals: HashMap<Box<str>, f64>,
    state: State,
    /// Blocks executed and not yet handed on.
    blocks: VecDeque<Block>,
    iterations: u64,
    /// Lines executed so far.
    executed: u64,
    options: Options,
    /// The main program's folder, searched first for subroutine files.
    folder: Option<PathBuf>,
    /// The program has ended (or failed).
    finished: bool,
    /// G70-G72: the profile being read, if any.
    lathe: Option<LatheRead>,
    /// Scratch space reused from line to line.
    text: String,
    line: Line,
    words: Vec<Word>,
    chars: Vec<char>,
    columns: Vec<usize>,
}

/// An error on line `line` of a source.
fn located(source: &Source<'_>, line: usize, e: LineError) -> GcodeError {
    GcodeError::Parse { file: source.name.clone(), line, column: e.column, message: e.message }
}

impl<'t> Runner<'t> {
    /// A program held in memory.
    pub(crate) fn in_memory(
        text: &'t str,
        file_name: &str,
        folder: Option<&Path>,
        options: &Options,
    ) -> Result<Runner<'t>, GcodeError> {
        Runner::new(Source::in_memory(std::borrow::Cow::Borrowed(text), file_name), folder, options)
    }

    /// A program file, read as it runs; errors name it as `path` displays.
    pub(crate) fn file(path: &Path, options: &Options) -> Result<Runner<'static>, GcodeError> {
        let name = path.display().to_string();
        let open = || Reader::open(path).map_err(|source| GcodeError::Io { file: name.clone(), source });
        let source = Source::new(std::borrow::Cow::Borrowed(""), open()?, open()?, &name);
        Runner::new(source, path.parent(), options)
    }

    fn new(main: Source<'t>, folder: Option<&Path>, options: &Options) -> Result<Runner<'t>, GcodeError> {
        crate::persistent::check(&options.parameters.values)?;
        let mut runner = Runner {
            sources: vec![main],
            frames: vec![Frame {
                source: 0,
                pc: Pc { offset: 0, line: 1 },
                params_saved: None,
                locals: HashMap::new(),
                repeats: HashMap::new(),
                labels: HashMap::new(),
                saved: None,
            }],
            globals: HashMap::new(),
            state: State::default(),
            blocks: VecDeque::new(),
            iterations: 0,
            executed: 0,
            options: options.clone(),
            folder: folder.map(Path::to_path_buf),
            finished: false,
            lathe: None,
            text: String::new(),
            line: Line::default(),
            words: Vec::new(),
            chars: Vec::new(),
            columns: Vec::new(),
        };
        runner.state.set_tools(&options.tools);
        runner.state.set_user_m_path(&options.user_m_path);
        runner.state.set_machine_unit(options.machine_unit_mm);
        runner.state.load_parameters(&options.parameters.values);
        // `#<_ini[section]name>`: each entry whose section and name are upper case (the
        // only ones LinuxCNC's upper-cased lookup finds) and whose value is a number.
        for ((section, name), value) in &options.ini {
            if let Ok(value) = value.parse::<f64>() {
                if *section == section.to_uppercase() && *name == name.to_uppercase() {
                    let key = format!("_ini[{}]{}", section.to_lowercase(), name.to_lowercase());
                    runner.globals.insert(key.into(), value);
                }
            }
        }
        // Scanned up to the first line with content: an empty program is refused.
        let main = &mut runner.sources[0];
        while main.content_lines == 0 && main.scan_one() {}
        if let Some(source) = main.failed.take() {
            return Err(GcodeError::Io { file: main.name.clone(), source });
        }
        if main.content_lines == 0 {
            return Err(GcodeError::Parse {
                file: main.name.clone(),
                line: 1,
                column: 1,
                message: "the program is empty (no blocks)".into(),
            });
        }
        Ok(runner)
    }

    /// The next block, `None` after the program's end; an error ends the program.
    pub(crate) fn next_block(&mut self) -> Option<Result<Block, GcodeError>> {
        loop {
            if let Some(block) = self.blocks.pop_front() {
                return Some(Ok(block));
            }
            if self.finished {
                return None;
            }
            match self.step() {
                Ok(true) => {}
                Ok(false) => {
                    self.finished = true;
                    if let Some((line, column)) = self.state.open_nurbs() {
                        return Some(Err(GcodeError::Parse {
                            file: self.sources[0].name.clone(),
                            line,
                            column,
                            message: "the program ends inside the NURBS block opened here (G5.3 missing)".into(),
                        }));
                    }
                }
                Err(e) => {
                    self.finished = true;
                    self.blocks.clear();
                    return Some(Err(e));
                }
            }
        }
    }

    /// The persistent parameters as the program leaves them: LinuxCNC's required ones and
    /// every one the parameter file held.
    pub(crate) fn parameters(&self) -> Parameters {
        let values = required_parameters()
            .chain(self.options.parameters.values.keys().copied())
            .map(|n| (n, self.state.parameter(n)))
            .collect();
        Parameters { values }
    }

    /// Lines the loaded files hold, every file scanned to its end first.
    fn lines_held(&mut self) -> u64 {
        self.sources
            .iter_mut()
            .map(|s| {
                s.scan_all();
                s.content_lines
            })
            .sum()
    }

    /// Executes the next line with content; false when the program has ended.
    fn step(&mut self) -> Result<bool, GcodeError> {
        let frame = self.frames.last().expect("a frame");
        let (s, mut pc) = (frame.source, frame.pc);
        // The next line with content, the scan past it; a line the scan lexed is not read.
        let (next, lexed) = loop {
            let source = &mut self.sources[s];
            source.scan_past(pc.offset);
            if let Some(e) = source.failed.take() {
                return Err(GcodeError::Io { file: source.name.clone(), source: e });
            }
            if let Some(i) = source.entry_at(pc.offset) {
                break (source.after_entry(i), Some(i));
            }
            let read = if source.end_offset.is_some_and(|end| pc.offset >= end) {
                Ok(None)
            } else {
                source.reader.read(&source.memory, pc.offset, &mut self.text)
            };
            let next = match read {
                Ok(Some(next)) => next,
                Ok(None) => {
                    if self.frames.len() > 1 {
                        let line = source.last_content_line;
                        return Err(located(
                            source,
                            line,
                            LineError::new(1, "the file ends inside a subroutine (endsub missing)"),
                        ));
                    }
                    return Ok(false);
                }
                Err(e) => return Err(GcodeError::Io { file: source.name.clone(), source: e }),
            };
            let (content, _) = scan(&self.text);
            // The opening `%` (the closing one ends the file above). A line of comments
            // alone is skipped unless its last one is active or its comments do not lex
            // (the lexer then says why, as rs274 refuses an unclosed or nested comment).
            let skipped = !content && matches!(crate::lexer::line_message(&self.text), Ok(None));
            if skipped || self.text.trim_matches([' ', '\t']) == "%" {
                pc = Pc { offset: next, line: pc.line + 1 };
                continue;
            }
            // A line with an `O` that the scan did not keep does not lex: lexed (and
            // refused) as an ordinary block.
            break (Pc { offset: next, line: pc.line + 1 }, None);
        };
        let entry = lexed.filter(|&i| self.sources[s].entries[i].lexed.oword.is_some());
        if let Some(i) = entry {
            let source = &mut self.sources[s];
            let o = oword(&source.entries[i]);
            match o.kind {
                OKind::Break | OKind::Continue => {
                    if let Some(start) = source.links[i].start {
                        source.settle(start)
                    }
                }
                OKind::If | OKind::Elseif | OKind::Else | OKind::While | OKind::Do | OKind::Repeat | OKind::Sub => {
                    source.settle(i)
                }
                _ => {}
            }
            if let Some(message) = &source.broken[i] {
                return Err(located(
                    source,
                    pc.line,
                    LineError::new(oword(&source.entries[i]).column, message.clone()),
                ));
            }
        }
        self.state.line = pc.line;
        self.executed += 1;
        if self.executed > MAX_REPEATED_LINES && self.executed > self.lines_held() + MAX_REPEATED_LINES {
            let column = entry.map_or(1, |i| oword(&self.sources[s].entries[i]).column);
            return Err(located(
                &self.sources[s],
                pc.line,
                LineError::new(
                    column,
                    format!("execution limit reached: loops and calls ran {MAX_REPEATED_LINES} lines again (a loop that never ends?)"),
                ),
            ));
        }
        self.frames.last_mut().expect("frame").pc = next;
        let step = match entry {
            Some(i) => self.oword(s, i),
            None => self.block(lexed.map(|i| (s, i))),
        };
        match step {
            Ok(go_on) => {
                if self.lathe.as_ref().is_some_and(|l| l.frames == self.frames.len()) {
                    self.finish_lathe()?;
                }
                Ok(go_on)
            }
            Err(e) => Err(located(&self.sources[s], pc.line, e)),
        }
    }

    /// The Q subroutine of a lathe cycle has returned: the cycle's moves from its
    /// profile, as blocks of the cycle's line.
    fn finish_lathe(&mut self) -> Result<(), GcodeError> {
        let l = self.lathe.take().expect("a lathe cycle");
        let at_cycle = |column: usize, message: String| GcodeError::Parse {
            file: self.sources[l.source].name.clone(),
            line: l.line,
            column,
            message,
        };
        self.state.profile_done(l.cycle.start);
        self.state.line = l.line;
        let moves = cycle_moves(&l.cycle, l.reader.segments)
            .map_err(|e| at_cycle(l.cycle.column, format!("G7X error: {}", e.0)))?;
        let kinds = self.state.lathe_moves(&moves, l.cycle.column).map_err(|e| at_cycle(e.column, e.message))?;
        self.blocks.extend(kinds.into_iter().map(|kind| Block { line: l.line, n: l.n, kind }));
        Ok(())
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

    fn jump(&mut self, to: Pc) {
        self.frames.last_mut().expect("frame").pc = to;
    }

    /// Executes the ordinary block in `self.text` (lexed already when `lexed` names its
    /// entry); false when it ends the program.
    fn block(&mut self, lexed: Option<(usize, usize)>) -> Result<bool, LineError> {
        let mut buffer = std::mem::take(&mut self.line);
        let mut words = std::mem::take(&mut self.words);
        words.clear();
        let line = match lexed {
            Some((s, i)) => &self.sources[s].entries[i].lexed,
            None => {
                lex_into(&self.text, &mut self.chars, &mut self.columns, &mut buffer)?;
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
        // The message comment, expanded once the assignments have taken effect.
        let message = line.message.clone();
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
        // As rs274, the comment acts first in its block; a lathe cycle's profile, read
        // rather than run, gives none.
        if let (Some(message), None) = (message, &self.lathe) {
            self.message(&message, &words)?;
        }
        if words.is_empty() {
            self.words = words;
            return Ok(true);
        }
        if let Some(lathe) = &mut self.lathe {
            let read = self.state.profile_line(&words, &mut lathe.reader);
            self.words = words;
            return read.map(|()| true);
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
        if let Some(cycle) = executed.lathe {
            // The profile: the Q subroutine, called, its motion read instead of run.
            let (q, column) = cycle.q;
            let o =
                OWord { label: format!("{}", q.round() as i64).into(), kind: OKind::Call, column, args: Vec::new() };
            let frames = self.frames.len();
            let source = self.frames.last().expect("frame").source;
            self.call(&o, &[])?;
            let reader = ProfileReader::new(cycle.start);
            self.lathe = Some(LatheRead { cycle, reader, frames, source, line, n: executed.n });
        }
        Ok(!executed.end)
    }

    /// Emits the block of an active comment (`words` are its line's, for the N number);
    /// ABORT's error, with its text, at the comment.
    fn message(&mut self, message: &LexedMessage, words: &[Word]) -> Result<(), LineError> {
        let scope = Scope {
            state: &self.state,
            locals: &self.frames.last().expect("frame").locals,
            globals: &self.globals,
            call_level: self.frames.len() - 1,
        };
        let kind = match message.kind {
            Active::Message(kind) => kind,
            // LinuxCNC's `convert_comment`: the text expanded as DEBUG's, the program
            // stopped with it as its error.
            Active::Abort => {
                let text = expand(&message.text, &scope);
                return Err(LineError::new(message.column, format!("ABORT:{text}")));
            }
            Active::Python => {
                return Err(LineError::new(
                    message.column,
                    format!("unsupported: (PY, ...) ({})", crate::unsupported::PYTHON),
                ))
            }
        };
        let text = match kind {
            MessageKind::Msg | MessageKind::LogOpen | MessageKind::LogAppend | MessageKind::LogClose => {
                message.text.to_string()
            }
            // rs274 shows a DEBUG only while #5599 is above 0 (1 at the start).
            MessageKind::Debug if scope.numbered(PARAM_DEBUG) <= 0.0 => return Ok(()),
            MessageKind::Debug | MessageKind::Print | MessageKind::Log => expand(&message.text, &scope),
        };
        let n = words.iter().find(|w| w.letter == 'N').map(|w| w.value as u32);
        self.blocks.push_back(Block { line: self.state.line, n, kind: BlockKind::Message { kind, text } });
        Ok(())
    }

    /// Executes an O-word line.
    fn oword(&mut self, s: usize, pc: usize) -> Result<bool, LineError> {
        let o = oword(&self.sources[s].entries[pc]).clone();
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
        // Until the scan has read the whole file, a label may yet be shared: each is kept.
        let opens = matches!(o.kind, OKind::If | OKind::While | OKind::Do | OKind::Repeat) && !links.closes_do;
        if links.shared_label || (opens && !self.sources[s].complete) {
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
            OKind::Sub => self.jump_after(s, links.end.ok_or_else(|| missing("sub"))?),
            OKind::Call => {
                self.jump_after(s, pc);
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
                        self.jump_after(s, at);
                        break;
                    }
                    let next = self.sources[s].links[at].next_branch.ok_or_else(|| missing("if"))?;
                    let entry = &self.sources[s].entries[next];
                    let branch = oword(entry);
                    match branch.kind {
                        OKind::Elseif => {
                            let cond = branch.args[0].clone();
                            let v = cond.eval(&self.scope()).map_err(|e| LineError::new(e.column, e.message))?;
                            at = next;
                            taken = v != 0.0;
                        }
                        OKind::Else => {
                            self.jump_after(s, next);
                            break;
                        }
                        _ => {
                            self.jump_after(s, next);
                            break;
                        }
                    }
                }
            }
            OKind::Elseif | OKind::Else => self.jump_after(s, links.end.ok_or_else(|| missing("elseif"))?),
            OKind::Endif | OKind::Do => self.jump_after(s, pc),
            OKind::While if links.closes_do => {
                if condition {
                    self.count_iteration(column)?;
                    self.jump_after(s, links.start.expect("do"));
                } else {
                    self.jump_after(s, pc);
                }
            }
            OKind::While => {
                if condition {
                    self.jump_after(s, pc);
                } else {
                    self.jump_after(s, links.end.ok_or_else(|| missing("while"))?);
                }
            }
            OKind::Endwhile => {
                self.count_iteration(column)?;
                self.jump_to(s, links.start.expect("while"));
            }
            OKind::Repeat => {
                let end = links.end.ok_or_else(|| missing("repeat"))?;
                let count = values[0].round();
                if count >= 1.0 {
                    self.frames.last_mut().expect("frame").repeats.insert(pc, count.min(u64::MAX as f64) as u64);
                    self.jump_after(s, pc);
                } else {
                    self.jump_after(s, end);
                }
            }
            OKind::Endrepeat => {
                let start = links.start.expect("repeat");
                let frame = self.frames.last_mut().expect("frame");
                let left = frame.repeats.get(&start).copied().unwrap_or(1).saturating_sub(1);
                if left > 0 {
                    frame.repeats.insert(start, left);
                    self.count_iteration(column)?;
                    self.jump_after(s, start);
                } else {
                    frame.repeats.remove(&start);
                    self.jump_after(s, pc);
                }
            }
            OKind::Break | OKind::Continue => {
                let start = links.start.expect("loop");
                let start_links = self.sources[s].links[start];
                let end = start_links.end.ok_or_else(|| missing("loop"))?;
                let start_kind = oword(&self.sources[s].entries[start]).kind;
                if o.kind == OKind::Break {
                    self.frames.last_mut().expect("frame").repeats.remove(&start);
                    self.jump_after(s, end);
                } else {
                    // continue: the while re-tests; a do's closing while tests; a repeat counts down.
                    match start_kind {
                        OKind::While => {
                            self.count_iteration(column)?;
                            self.jump_to(s, start)
                        }
                        _ => self.jump_to(s, end),
                    }
                }
            }
        }
        Ok(true)
    }

    /// Runs entry `i` of source `s` next.
    fn jump_to(&mut self, s: usize, i: usize) {
        let to = self.sources[s].at_entry(i);
        self.jump(to);
    }

    /// Runs the line after entry `i` of source `s` next.
    fn jump_after(&mut self, s: usize, i: usize) {
        let to = self.sources[s].after_entry(i);
        self.jump(to);
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
            .find_map(|s| self.sources[s].sub(&o.label).map(|e| (s, e)));
        let (s, entry) = match found {
            Some(found) => found,
            None => self.load_sub_file(o)?,
        };
        self.sources[s].settle(entry);
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
            pc: self.sources[s].after_entry(entry),
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
                let mut source = Source::in_memory(std::borrow::Cow::Owned(text), &path.display().to_string());
                source.scan_all();
                let entry = source.subs.get(&o.label).copied();
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
