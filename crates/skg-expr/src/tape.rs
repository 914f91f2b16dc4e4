//! Compiled evaluation tapes: straight-line programs over a register file.

use crate::graph::{ExprId, Graph};
use crate::hash::FxMap;
use crate::node::{powi, Func, Node};

/// Operation of a run of instructions.
#[derive(Copy, Clone, Debug, PartialEq, Eq, Hash)]
enum Op {
    /// `d = vars[a]`
    Load,
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    /// `d = atan2(a, b)`
    Atan2,
    /// `d = a + consts[b]`
    AddC,
    /// `d = consts[b] * a`
    MulC,
    /// `d = consts[b] - a`
    CSub,
    /// `d = a / consts[b]`
    DivC,
    /// `d = consts[b] / a`
    CDiv,
    /// `d = a ^ consts[b]`
    PowC,
    Neg,
    /// `d = a * a`
    Sq,
    /// `d = a ^ (b as i32)`
    Powi,
    Sin,
    Cos,
    Tan,
    Exp,
    Ln,
    Sqrt,
    Abs,
    Sinh,
    Cosh,
    Tanh,
    Atan,
}

const N_OPS: usize = Op::Atan as usize + 1;

impl Op {
    fn of_func(f: Func) -> Op {
        match f {
            Func::Sin => Op::Sin,
            Func::Cos => Op::Cos,
            Func::Tan => Op::Tan,
            Func::Exp => Op::Exp,
            Func::Log => Op::Ln,
            Func::Sqrt => Op::Sqrt,
            Func::Abs => Op::Abs,
            Func::Sinh => Op::Sinh,
            Func::Cosh => Op::Cosh,
            Func::Tanh => Op::Tanh,
            Func::Atan => Op::Atan,
        }
    }

    /// What the `b` field of an instruction with this operation holds.
    fn b_kind(self) -> BKind {
        match self {
            Op::Add | Op::Sub | Op::Mul | Op::Div | Op::Pow | Op::Atan2 => BKind::Reg,
            Op::AddC | Op::MulC | Op::CSub | Op::DivC | Op::CDiv | Op::PowC => BKind::Const,
            _ => BKind::Unused,
        }
    }
}

#[derive(Copy, Clone, Debug, PartialEq, Eq)]
enum BKind {
    Reg,
    Const,
    Unused,
}

/// One instruction: destination register `d`, operand register `a` (a variable index for
/// `Load`), and `b`: a second operand register, an index into the constant table, or an
/// integer exponent, depending on the operation of the run the instruction is in.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
struct Ins {
    d: u32,
    a: u32,
    b: u32,
}

/// A run of `len` consecutive instructions with the same operation. The instructions of
/// a run are independent of each other, so the processor can overlap them.
#[derive(Copy, Clone, Debug, PartialEq, Eq)]
struct Run {
    op: Op,
    len: u32,
}

/// An immediate operand of an instruction before register allocation.
#[derive(Copy, Clone, Debug)]
enum Imm {
    None,
    F(f64),
    I(i32),
}

/// A compiled straight-line program computing several outputs at once.
///
/// Built by [`Tape::compile`] from any set of expressions of one [`Graph`]: the union of
/// their sub-DAGs becomes one instruction per non-constant node (so subexpressions shared
/// between outputs, e.g. between a gradient and a Hessian, are computed once per
/// evaluation), with constants folded into the instructions as immediates where the
/// operation allows it and registers reused once their value is dead. Instructions are
/// scheduled in runs of independent instructions with the same operation, so that
/// [`Tape::eval`] dispatches once per run rather than once per instruction and the
/// processor can overlap the instructions of a run. Evaluation does not allocate; a tape
/// is immutable, so one tape can be evaluated from many threads, each with its own
/// scratch buffer.
#[derive(Clone, Debug)]
pub struct Tape {
    code: Vec<Ins>,
    runs: Vec<Run>,
    consts: Vec<f64>,
    /// Registers `0..const_regs.len()` hold these constants (operands that could not be
    /// folded into an instruction, and constant outputs).
    const_regs: Vec<f64>,
    /// The register holding each output.
    outs: Vec<u32>,
    n_vars: usize,
    scratch_len: usize,
}

/// An instruction before scheduling and register allocation.
#[derive(Copy, Clone, Debug)]
struct Lowered {
    node: ExprId,
    op: Op,
    imm: Imm,
    ops: [ExprId; 2],
    nops: usize,
}

/// Step 1 of [`Tape::compile`]: lowers a non-constant node to an instruction whose
/// register operands may be constant nodes that need a register of their own; `None` for
/// a constant node.
fn lower(graph: &Graph, n: ExprId, n_vars: usize) -> Option<Lowered> {
    let k = |e: ExprId| graph.as_constant(e);
    let z = ExprId(0);
    let (op, imm, ops, nops) = match graph.node(n) {
        Node::Const(_) => return None,
        Node::Var(v) => {
            assert!((v as usize) < n_vars, "Tape::compile: an output depends on variable {v} but n_vars = {n_vars}");
            (Op::Load, Imm::I(v as i32), [z, z], 0)
        }
        Node::Add(a, b) => match (k(a), k(b)) {
            (Some(c), _) => (Op::AddC, Imm::F(c), [b, z], 1),
            (_, Some(c)) => (Op::AddC, Imm::F(c), [a, z], 1),
            _ => (Op::Add, Imm::None, [a, b], 2),
        },
        // a - c == a + (-c) exactly in IEEE arithmetic
        Node::Sub(a, b) => match (k(a), k(b)) {
            (Some(c), _) => (Op::CSub, Imm::F(c), [b, z], 1),
            (_, Some(c)) => (Op::AddC, Imm::F(-c), [a, z], 1),
            _ => (Op::Sub, Imm::None, [a, b], 2),
        },
        Node::Mul(a, b) => match (k(a), k(b)) {
            (Some(c), _) => (Op::MulC, Imm::F(c), [b, z], 1),
            (_, Some(c)) => (Op::MulC, Imm::F(c), [a, z], 1),
            _ if a == b => (Op::Sq, Imm::None, [a, z], 1),
            _ => (Op::Mul, Imm::None, [a, b], 2),
        },
        Node::Div(a, b) => match (k(a), k(b)) {
            (Some(c), _) => (Op::CDiv, Imm::F(c), [b, z], 1),
            (_, Some(c)) => (Op::DivC, Imm::F(c), [a, z], 1),
            _ => (Op::Div, Imm::None, [a, b], 2),
        },
        Node::Pow(a, b) => match k(b) {
            Some(c) => (Op::PowC, Imm::F(c), [a, z], 1),
            None => (Op::Pow, Imm::None, [a, b], 2),
        },
        Node::Atan2(y, x) => (Op::Atan2, Imm::None, [y, x], 2),
        Node::Neg(a) => (Op::Neg, Imm::None, [a, z], 1),
        Node::Powi(a, 2) => (Op::Sq, Imm::None, [a, z], 1),
        Node::Powi(a, m) => (Op::Powi, Imm::I(m), [a, z], 1),
        Node::Func(f, a) => (Op::of_func(f), Imm::None, [a, z], 1),
    };
    Some(Lowered { node: n, op, imm, ops, nops })
}

/// Step 2 of [`Tape::compile`]: the order of the instructions (indices into `lowered`)
/// and its runs. Repeatedly takes all ready instructions of the operation that has the
/// most ready ones as one run; instructions ready at the same time are independent.
fn schedule(lowered: &[Lowered]) -> (Vec<usize>, Vec<Run>) {
    let index: FxMap<ExprId, usize> = lowered.iter().enumerate().map(|(i, l)| (l.node, i)).collect();
    let mut users: Vec<Vec<usize>> = vec![Vec::new(); lowered.len()];
    let mut pending = vec![0usize; lowered.len()];
    for (i, l) in lowered.iter().enumerate() {
        let mut ops = l.ops[..l.nops].to_vec();
        ops.dedup();
        for o in ops {
            if let Some(&j) = index.get(&o) {
                users[j].push(i);
                pending[i] += 1;
            }
        }
    }
    let mut ready: Vec<Vec<usize>> = vec![Vec::new(); N_OPS];
    for (i, l) in lowered.iter().enumerate() {
        if pending[i] == 0 {
            ready[l.op as usize].push(i);
        }
    }
    let mut schedule: Vec<usize> = Vec::with_capacity(lowered.len());
    let mut runs: Vec<Run> = Vec::new();
    while let Some(best) = (0..N_OPS).filter(|&o| !ready[o].is_empty()).max_by_key(|&o| ready[o].len()) {
        let batch = std::mem::take(&mut ready[best]);
        runs.push(Run { op: lowered[batch[0]].op, len: batch.len() as u32 });
        for &i in &batch {
            for &u in &users[i] {
                pending[u] -= 1;
                if pending[u] == 0 {
                    ready[lowered[u].op as usize].push(u);
                }
            }
        }
        schedule.extend(batch);
    }
    debug_assert_eq!(schedule.len(), lowered.len());
    (schedule, runs)
}

/// Step 3 of [`Tape::compile`]: constant nodes that are register operands or outputs get
/// permanent registers at the front of the register file. Returns their values and the
/// register of each.
fn constant_registers(graph: &Graph, lowered: &[Lowered], outputs: &[ExprId]) -> (Vec<f64>, FxMap<ExprId, u32>) {
    let mut const_regs: Vec<f64> = Vec::new();
    let mut reg: FxMap<ExprId, u32> = FxMap::default();
    let operands = lowered.iter().flat_map(|l| l.ops[..l.nops].to_vec());
    for o in operands.chain(outputs.iter().copied()) {
        if let Some(c) = graph.as_constant(o) {
            reg.entry(o).or_insert_with(|| {
                const_regs.push(c);
                (const_regs.len() - 1) as u32
            });
        }
    }
    (const_regs, reg)
}

/// Step 4 of [`Tape::compile`], liveness: the position in the schedule of the last
/// instruction reading each node.
fn last_uses(lowered: &[Lowered], schedule: &[usize]) -> FxMap<ExprId, usize> {
    let mut last_use: FxMap<ExprId, usize> = FxMap::default();
    for (pos, &i) in schedule.iter().enumerate() {
        let l = &lowered[i];
        for &o in &l.ops[..l.nops] {
            last_use.insert(o, pos);
        }
    }
    last_use
}

/// The instructions and constant table of a tape, and the length of its register file.
struct Emitted {
    code: Vec<Ins>,
    consts: Vec<f64>,
    scratch_len: u32,
}

/// Step 5 of [`Tape::compile`]: register allocation (a register is reused once its value
/// is dead; the first `first_free` registers hold constants) and emission of the
/// instructions in schedule order, immediates placed in the constant table. Adds the
/// register of every instruction's node to `reg`.
fn allocate_and_emit(
    graph: &Graph,
    lowered: &[Lowered],
    schedule: &[usize],
    outputs: &[ExprId],
    last_use: &FxMap<ExprId, usize>,
    reg: &mut FxMap<ExprId, u32>,
    first_free: u32,
) -> Emitted {
    let is_output: FxMap<ExprId, ()> = outputs.iter().map(|&o| (o, ())).collect();
    let mut consts: Vec<f64> = Vec::new();
    let mut const_index: FxMap<u64, u32> = FxMap::default();
    let mut free: Vec<u32> = Vec::new();
    let mut next = first_free;
    let mut code = Vec::with_capacity(schedule.len());
    for (pos, &i) in schedule.iter().enumerate() {
        let l = lowered[i];
        let a = if l.nops > 0 { reg[&l.ops[0]] } else { 0 };
        let b = if l.nops > 1 { reg[&l.ops[1]] } else { 0 };
        for (j, &o) in l.ops[..l.nops].iter().enumerate() {
            let dup = j == 1 && l.ops[0] == o;
            if !dup && last_use.get(&o) == Some(&pos) && !is_output.contains_key(&o) && graph.as_constant(o).is_none() {
                free.push(reg[&o]);
            }
        }
        let d = free.pop().unwrap_or_else(|| {
            next += 1;
            next - 1
        });
        reg.insert(l.node, d);
        let (a, b) = match (l.op, l.imm) {
            (Op::Load, Imm::I(v)) => (v as u32, 0),
            (_, Imm::I(m)) => (a, m as u32),
            (_, Imm::F(c)) => {
                let k = *const_index.entry(c.to_bits()).or_insert_with(|| {
                    consts.push(c);
                    (consts.len() - 1) as u32
                });
                (a, k)
            }
            (_, Imm::None) => (a, b),
        };
        code.push(Ins { d, a, b });
    }
    Emitted { code, consts, scratch_len: next }
}

impl Tape {
    /// Compile `outputs` of `graph` into a tape reading a variable vector of length
    /// `n_vars`.
    ///
    /// # Panics
    /// If an output depends on a variable with index `>= n_vars`.
    pub fn compile(graph: &Graph, outputs: &[ExprId], n_vars: usize) -> Tape {
        let order = graph.reachable(outputs);
        let lowered: Vec<Lowered> = order.iter().filter_map(|&n| lower(graph, n, n_vars)).collect();
        let (schedule, runs) = schedule(&lowered);
        let (const_regs, mut reg) = constant_registers(graph, &lowered, outputs);
        let last_use = last_uses(&lowered, &schedule);
        let emitted = allocate_and_emit(graph, &lowered, &schedule, outputs, &last_use, &mut reg, const_regs.len() as u32);
        let outs = outputs
            .iter()
            .map(|&o| {
                if let Some(v) = graph.as_var(o) {
                    assert!(v < n_vars, "Tape::compile: an output is variable {v} but n_vars = {n_vars}");
                }
                reg[&o]
            })
            .collect();
        let Emitted { code, consts, scratch_len } = emitted;
        let tape = Tape { code, runs, consts, const_regs, outs, n_vars, scratch_len: scratch_len as usize };
        tape.validate();
        tape
    }

    /// Check every index the evaluation loop uses without bounds checks.
    fn validate(&self) {
        let s = self.scratch_len as u32;
        let total: usize = self.runs.iter().map(|r| r.len as usize).sum();
        assert_eq!(total, self.code.len(), "Tape runs do not cover the code");
        let mut pos = 0;
        for run in &self.runs {
            for ins in &self.code[pos..pos + run.len as usize] {
                let a_ok = if run.op == Op::Load { (ins.a as usize) < self.n_vars } else { ins.a < s };
                let b_ok = match run.op.b_kind() {
                    BKind::Reg => ins.b < s,
                    BKind::Const => (ins.b as usize) < self.consts.len(),
                    BKind::Unused => true,
                };
                assert!(ins.d < s && a_ok && b_ok, "Tape::compile produced an out-of-range index in {ins:?}");
            }
            pos += run.len as usize;
        }
        assert!(self.outs.iter().all(|&r| r < s));
        assert!(self.const_regs.len() <= self.scratch_len);
    }

    /// Number of runs of same-operation instructions (the number of dispatches per
    /// evaluation).
    pub fn n_runs(&self) -> usize {
        self.runs.len()
    }

    /// Number of outputs.
    pub fn n_outputs(&self) -> usize {
        self.outs.len()
    }

    /// Length of the variable vector the tape reads.
    pub fn n_vars(&self) -> usize {
        self.n_vars
    }

    /// Number of instructions (including loads of variables).
    pub fn len(&self) -> usize {
        self.code.len()
    }

    /// True if the tape has no instructions (all outputs are constants or variables).
    pub fn is_empty(&self) -> bool {
        self.code.is_empty()
    }

    /// Length of the scratch buffer [`Tape::eval`] needs.
    pub fn scratch_len(&self) -> usize {
        self.scratch_len
    }

    /// Evaluate all outputs at `vars` (`vars[i]` is variable `i`) into `outputs`, using
    /// `scratch` as the register file. Does not allocate.
    ///
    /// # Panics
    /// If `vars.len() < self.n_vars()`, `scratch.len() < self.scratch_len()` or
    /// `outputs.len() != self.n_outputs()`.
    pub fn eval(&self, vars: &[f64], scratch: &mut [f64], outputs: &mut [f64]) {
        assert!(vars.len() >= self.n_vars, "Tape::eval: {} variables given, the tape reads {}", vars.len(), self.n_vars);
        assert!(
            scratch.len() >= self.scratch_len,
            "Tape::eval: scratch of length {} given, the tape needs {}",
            scratch.len(),
            self.scratch_len
        );
        assert_eq!(outputs.len(), self.outs.len(), "Tape::eval: wrong number of outputs");
        let s = &mut scratch[..self.scratch_len];
        s[..self.const_regs.len()].copy_from_slice(&self.const_regs);
        let k = &self.consts[..];
        let code = &self.code[..];
        // SAFETY: `validate` (run by `compile`, the only constructor) checked that the runs
        // cover the code exactly, and that every register index is < scratch_len, every
        // constant index < consts.len() and every variable index < n_vars; the asserts
        // above guarantee that the slices are that long.
        unsafe {
            macro_rules! r {
                ($i:expr) => {
                    *s.get_unchecked($i as usize)
                };
            }
            macro_rules! c {
                ($i:expr) => {
                    *k.get_unchecked($i as usize)
                };
            }
            macro_rules! each {
                ($chunk:expr, |$i:ident| $v:expr) => {
                    for $i in $chunk {
                        let v = $v;
                        *s.get_unchecked_mut($i.d as usize) = v;
                    }
                };
            }
            let mut pos = 0usize;
            for run in &self.runs {
                let end = pos + run.len as usize;
                let chunk = code.get_unchecked(pos..end);
                pos = end;
                match run.op {
                    Op::Load => each!(chunk, |i| *vars.get_unchecked(i.a as usize)),
                    Op::Add => each!(chunk, |i| r!(i.a) + r!(i.b)),
                    Op::Sub => each!(chunk, |i| r!(i.a) - r!(i.b)),
                    Op::Mul => each!(chunk, |i| r!(i.a) * r!(i.b)),
                    Op::Div => each!(chunk, |i| r!(i.a) / r!(i.b)),
                    Op::Pow => each!(chunk, |i| r!(i.a).powf(r!(i.b))),
                    Op::Atan2 => each!(chunk, |i| r!(i.a).atan2(r!(i.b))),
                    Op::AddC => each!(chunk, |i| r!(i.a) + c!(i.b)),
                    Op::MulC => each!(chunk, |i| c!(i.b) * r!(i.a)),
                    Op::CSub => each!(chunk, |i| c!(i.b) - r!(i.a)),
                    Op::DivC => each!(chunk, |i| r!(i.a) / c!(i.b)),
                    Op::CDiv => each!(chunk, |i| c!(i.b) / r!(i.a)),
                    Op::PowC => each!(chunk, |i| r!(i.a).powf(c!(i.b))),
                    Op::Neg => each!(chunk, |i| -r!(i.a)),
                    Op::Sq => each!(chunk, |i| r!(i.a) * r!(i.a)),
                    Op::Powi => each!(chunk, |i| powi(r!(i.a), i.b as i32)),
                    Op::Sin => each!(chunk, |i| r!(i.a).sin()),
                    Op::Cos => each!(chunk, |i| r!(i.a).cos()),
                    Op::Tan => each!(chunk, |i| r!(i.a).tan()),
                    Op::Exp => each!(chunk, |i| r!(i.a).exp()),
                    Op::Ln => each!(chunk, |i| r!(i.a).ln()),
                    Op::Sqrt => each!(chunk, |i| r!(i.a).sqrt()),
                    Op::Abs => each!(chunk, |i| r!(i.a).abs()),
                    Op::Sinh => each!(chunk, |i| r!(i.a).sinh()),
                    Op::Cosh => each!(chunk, |i| r!(i.a).cosh()),
                    Op::Tanh => each!(chunk, |i| r!(i.a).tanh()),
                    Op::Atan => each!(chunk, |i| r!(i.a).atan()),
                }
            }
            for (o, &r) in outputs.iter_mut().zip(&self.outs) {
                *o = r!(r);
            }
        }
    }

    /// Evaluate all outputs into a new vector (allocates; convenient for tests).
    pub fn eval_vec(&self, vars: &[f64]) -> Vec<f64> {
        let mut scratch = vec![0.0; self.scratch_len];
        let mut out = vec![0.0; self.outs.len()];
        self.eval(vars, &mut scratch, &mut out);
        out
    }
}
