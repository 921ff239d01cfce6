//! Arithmetic expressions of x, y, z and t for boundary values, sources and initial fields.
//!
//! Grammar: numbers, the variables `x y z t`, the constants `pi e`, `+ - * / ^`,
//! comparisons `< <= > >=` (1 when true, 0 when false), parentheses and the functions
//! `exp ln log10 sqrt abs sin cos tan atan sinh cosh tanh floor ceil` (one argument)
//! and `min max pow atan2` (two). Parsed once into a tree, evaluated without allocation.
//! Written here rather than taken from evalexpr because that crate namespaces the math
//! functions (`math::exp`) and evaluates through a string-keyed context, which is slow
//! when a source is evaluated at every node of every step.

use crate::error::{Error, Result};
use crate::limits::{MAX_EXPR_DEPTH, MAX_EXPR_LEN};

/// A parsed expression of (x, y, z, t); two expressions are equal when their texts are.
#[derive(Debug, Clone)]
pub struct Expr {
    text: String,
    root: Node,
}

impl PartialEq for Expr {
    fn eq(&self, other: &Self) -> bool {
        self.text == other.text
    }
}

#[derive(Debug, Clone)]
enum Node {
    Num(f64),
    Var(usize),
    Neg(Box<Node>),
    Bin(Op, Box<Node>, Box<Node>),
    F1(fn(f64) -> f64, Box<Node>),
    F2(fn(f64, f64) -> f64, Box<Node>, Box<Node>),
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Op {
    Add,
    Sub,
    Mul,
    Div,
    Pow,
    Lt,
    Le,
    Gt,
    Ge,
}

impl Expr {
    /// Parses `text`; errors name the expression and the position. Texts longer than
    /// [`MAX_EXPR_LEN`] and trees deeper than [`MAX_EXPR_DEPTH`] are refused, so neither the
    /// parser nor the evaluator recurses without a bound.
    pub fn parse(text: &str) -> Result<Self> {
        if text.len() > MAX_EXPR_LEN {
            let head: String = text.chars().take(24).collect();
            return Err(Error::Expr {
                expr: format!("{head}…"),
                message: format!(
                    "is {} bytes long; at most {MAX_EXPR_LEN} are allowed",
                    text.len()
                ),
            });
        }
        let mut p = Parser {
            s: text.as_bytes(),
            i: 0,
            text,
            depth: 0,
        };
        let root = p.comparison()?;
        p.skip_ws();
        if p.i != p.s.len() {
            return Err(p.err("unexpected character"));
        }
        if depth(&root) > MAX_EXPR_DEPTH {
            return Err(p.err(&format!(
                "nests deeper than {MAX_EXPR_DEPTH} levels; split it or simplify it"
            )));
        }
        Ok(Expr {
            text: text.to_string(),
            root: fold(root),
        })
    }

    /// A constant expression.
    pub fn constant(v: f64) -> Self {
        Expr {
            text: format!("{v}"),
            root: Node::Num(v),
        }
    }

    /// The source text.
    pub fn text(&self) -> &str {
        &self.text
    }

    /// Evaluates at position (x, y, z) and time t.
    pub fn eval(&self, x: f64, y: f64, z: f64, t: f64) -> f64 {
        eval(&self.root, &[x, y, z, t])
    }

    /// True when the expression does not use t.
    pub fn is_time_independent(&self) -> bool {
        !uses(&self.root, 3)
    }

    /// True when the expression uses none of x, y, z.
    pub fn is_uniform(&self) -> bool {
        !uses(&self.root, 0) && !uses(&self.root, 1) && !uses(&self.root, 2)
    }
}

/// Depth of the tree, by an explicit stack (the tree may be deeper than the limit).
fn depth(root: &Node) -> usize {
    let mut stack = vec![(root, 1usize)];
    let mut deepest = 0;
    while let Some((n, d)) = stack.pop() {
        deepest = deepest.max(d);
        match n {
            Node::Num(_) | Node::Var(_) => {}
            Node::Neg(a) | Node::F1(_, a) => stack.push((a, d + 1)),
            Node::Bin(_, a, b) | Node::F2(_, a, b) => {
                stack.push((a, d + 1));
                stack.push((b, d + 1));
            }
        }
    }
    deepest
}

fn uses(n: &Node, var: usize) -> bool {
    match n {
        Node::Num(_) => false,
        Node::Var(v) => *v == var,
        Node::Neg(a) | Node::F1(_, a) => uses(a, var),
        Node::Bin(_, a, b) | Node::F2(_, a, b) => uses(a, var) || uses(b, var),
    }
}

/// The tree with every subtree that uses none of x, y, z, t replaced by its value (the same
/// operations on the same numbers: evaluation gives the same bits, with fewer nodes per call).
/// Recursion is bounded by [`MAX_EXPR_DEPTH`], checked before.
fn fold(n: Node) -> Node {
    let n = match n {
        Node::Neg(a) => Node::Neg(Box::new(fold(*a))),
        Node::F1(f, a) => Node::F1(f, Box::new(fold(*a))),
        Node::F2(f, a, b) => Node::F2(f, Box::new(fold(*a)), Box::new(fold(*b))),
        Node::Bin(op, a, b) => Node::Bin(op, Box::new(fold(*a)), Box::new(fold(*b))),
        leaf => leaf,
    };
    let constant = match &n {
        Node::Neg(a) | Node::F1(_, a) => matches!(**a, Node::Num(_)),
        Node::F2(_, a, b) | Node::Bin(_, a, b) => {
            matches!(**a, Node::Num(_)) && matches!(**b, Node::Num(_))
        }
        _ => false,
    };
    if constant {
        Node::Num(eval(&n, &[0.0; 4]))
    } else {
        n
    }
}

fn eval(n: &Node, v: &[f64; 4]) -> f64 {
    match n {
        Node::Num(c) => *c,
        Node::Var(i) => v[*i],
        Node::Neg(a) => -eval(a, v),
        Node::F1(f, a) => f(eval(a, v)),
        Node::F2(f, a, b) => f(eval(a, v), eval(b, v)),
        Node::Bin(op, a, b) => {
            let (a, b) = (eval(a, v), eval(b, v));
            let truth = |c: bool| if c { 1.0 } else { 0.0 };
            match op {
                Op::Add => a + b,
                Op::Sub => a - b,
                Op::Mul => a * b,
                Op::Div => a / b,
                Op::Pow => a.powf(b),
                Op::Lt => truth(a < b),
                Op::Le => truth(a <= b),
                Op::Gt => truth(a > b),
                Op::Ge => truth(a >= b),
            }
        }
    }
}

struct Parser<'a> {
    s: &'a [u8],
    i: usize,
    text: &'a str,
    /// Current recursion depth of the descent (bounded by [`MAX_EXPR_DEPTH`]).
    depth: usize,
}

impl Parser<'_> {
    fn err(&self, msg: &str) -> Error {
        // a long text is shown by its head: the message stays one readable line
        let expr = if self.text.len() > 80 {
            format!("{}…", self.text.chars().take(40).collect::<String>())
        } else {
            self.text.to_string()
        };
        Error::Expr {
            expr,
            message: format!("{msg} at position {}", self.i + 1),
        }
    }
    fn skip_ws(&mut self) {
        while self.i < self.s.len() && self.s[self.i].is_ascii_whitespace() {
            self.i += 1;
        }
    }
    fn peek(&mut self) -> Option<u8> {
        self.skip_ws();
        self.s.get(self.i).copied()
    }
    fn eat(&mut self, c: u8) -> bool {
        if self.peek() == Some(c) {
            self.i += 1;
            true
        } else {
            false
        }
    }
    /// Enters one level of recursion, refusing past [`MAX_EXPR_DEPTH`].
    fn enter(&mut self) -> Result<()> {
        self.depth += 1;
        if self.depth > MAX_EXPR_DEPTH {
            return Err(self.err(&format!(
                "nests deeper than {MAX_EXPR_DEPTH} levels; split it or simplify it"
            )));
        }
        Ok(())
    }
    fn comparison(&mut self) -> Result<Node> {
        self.enter()?;
        let n = self.comparison_inner();
        self.depth -= 1;
        n
    }
    fn comparison_inner(&mut self) -> Result<Node> {
        let lhs = self.sum()?;
        let op = match self.peek() {
            Some(b'<') => Op::Lt,
            Some(b'>') => Op::Gt,
            _ => return Ok(lhs),
        };
        self.i += 1;
        let op = if self.eat(b'=') {
            if op == Op::Lt {
                Op::Le
            } else {
                Op::Ge
            }
        } else {
            op
        };
        let rhs = self.sum()?;
        Ok(Node::Bin(op, Box::new(lhs), Box::new(rhs)))
    }
    fn sum(&mut self) -> Result<Node> {
        let mut lhs = self.product()?;
        loop {
            let op = if self.eat(b'+') {
                Op::Add
            } else if self.eat(b'-') {
                Op::Sub
            } else {
                return Ok(lhs);
            };
            let rhs = self.product()?;
            lhs = Node::Bin(op, Box::new(lhs), Box::new(rhs));
        }
    }
    fn product(&mut self) -> Result<Node> {
        let mut lhs = self.unary()?;
        loop {
            let op = if self.eat(b'*') {
                Op::Mul
            } else if self.eat(b'/') {
                Op::Div
            } else {
                return Ok(lhs);
            };
            let rhs = self.unary()?;
            lhs = Node::Bin(op, Box::new(lhs), Box::new(rhs));
        }
    }
    fn unary(&mut self) -> Result<Node> {
        self.enter()?;
        let n = self.unary_inner();
        self.depth -= 1;
        n
    }
    fn unary_inner(&mut self) -> Result<Node> {
        if self.eat(b'-') {
            return Ok(Node::Neg(Box::new(self.unary()?)));
        }
        if self.eat(b'+') {
            return self.unary();
        }
        self.power()
    }
    fn power(&mut self) -> Result<Node> {
        let base = self.atom()?;
        if self.eat(b'^') {
            // right associative, binds tighter than unary minus on the left: -2^2 = -4
            let exp = self.unary()?;
            return Ok(Node::Bin(Op::Pow, Box::new(base), Box::new(exp)));
        }
        Ok(base)
    }
    fn atom(&mut self) -> Result<Node> {
        match self.peek() {
            None => Err(self.err("unexpected end")),
            Some(b'(') => {
                self.i += 1;
                let n = self.comparison()?;
                if !self.eat(b')') {
                    return Err(self.err("expected `)`"));
                }
                Ok(n)
            }
            Some(c) if c.is_ascii_digit() || c == b'.' => self.number(),
            Some(c) if c.is_ascii_alphabetic() || c == b'_' => self.name(),
            Some(_) => Err(self.err("unexpected character")),
        }
    }
    fn number(&mut self) -> Result<Node> {
        let start = self.i;
        while self.i < self.s.len() && (self.s[self.i].is_ascii_digit() || self.s[self.i] == b'.') {
            self.i += 1;
        }
        if self.i < self.s.len() && (self.s[self.i] == b'e' || self.s[self.i] == b'E') {
            let save = self.i;
            self.i += 1;
            if self.i < self.s.len() && (self.s[self.i] == b'+' || self.s[self.i] == b'-') {
                self.i += 1;
            }
            if self.i < self.s.len() && self.s[self.i].is_ascii_digit() {
                while self.i < self.s.len() && self.s[self.i].is_ascii_digit() {
                    self.i += 1;
                }
            } else {
                self.i = save;
            }
        }
        let txt = &self.text[start..self.i];
        txt.parse::<f64>()
            .map(Node::Num)
            .map_err(|_| self.err(&format!("bad number `{txt}`")))
    }
    fn name(&mut self) -> Result<Node> {
        let start = self.i;
        while self.i < self.s.len()
            && (self.s[self.i].is_ascii_alphanumeric() || self.s[self.i] == b'_')
        {
            self.i += 1;
        }
        let name = &self.text[start..self.i];
        match name {
            "x" => return Ok(Node::Var(0)),
            "y" => return Ok(Node::Var(1)),
            "z" => return Ok(Node::Var(2)),
            "t" => return Ok(Node::Var(3)),
            "pi" => return Ok(Node::Num(std::f64::consts::PI)),
            "e" => return Ok(Node::Num(std::f64::consts::E)),
            _ => {}
        }
        let f1: Option<fn(f64) -> f64> = match name {
            "exp" => Some(f64::exp),
            "ln" => Some(f64::ln),
            "log10" => Some(f64::log10),
            "sqrt" => Some(f64::sqrt),
            "abs" => Some(f64::abs),
            "sin" => Some(f64::sin),
            "cos" => Some(f64::cos),
            "tan" => Some(f64::tan),
            "atan" => Some(f64::atan),
            "sinh" => Some(f64::sinh),
            "cosh" => Some(f64::cosh),
            "tanh" => Some(f64::tanh),
            "floor" => Some(f64::floor),
            "ceil" => Some(f64::ceil),
            _ => None,
        };
        let f2: Option<fn(f64, f64) -> f64> = match name {
            "min" => Some(f64::min),
            "max" => Some(f64::max),
            "pow" => Some(f64::powf),
            "atan2" => Some(f64::atan2),
            _ => None,
        };
        if f1.is_none() && f2.is_none() {
            self.i = start;
            return Err(self.err(&format!(
                "unknown name `{name}` (variables: x y z t; constants: pi e)"
            )));
        }
        if !self.eat(b'(') {
            return Err(self.err(&format!("expected `(` after `{name}`")));
        }
        let a = self.comparison()?;
        let node = if let Some(f) = f1 {
            Node::F1(f, Box::new(a))
        } else {
            if !self.eat(b',') {
                return Err(self.err(&format!("`{name}` takes two arguments")));
            }
            let b = self.comparison()?;
            Node::F2(f2.expect("checked above"), Box::new(a), Box::new(b))
        };
        if !self.eat(b')') {
            return Err(self.err("expected `)`"));
        }
        Ok(node)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn evaluates_the_thermal_shock_boundary_value() {
        let e = Expr::parse("5*t*exp(-2*t)").unwrap();
        let t: f64 = 0.7;
        assert_eq!(e.eval(0.0, 0.0, 0.0, t), 5.0 * t * (-2.0 * t).exp());
        assert!(!e.is_time_independent());
        assert!(e.is_uniform());
    }

    #[test]
    fn precedence_and_comparisons() {
        let e = Expr::parse("-2^2 + 3*(x<5) + 1e-1*y - z/2").unwrap();
        assert!((e.eval(1.0, 10.0, 4.0, 0.0) - (-4.0 + 3.0 + 1.0 - 2.0)).abs() < 1e-15);
        assert_eq!(e.eval(6.0, 0.0, 0.0, 0.0), -4.0);
        assert_eq!(
            Expr::parse("max(x, 2) + pow(2, 3)")
                .unwrap()
                .eval(1.0, 0.0, 0.0, 0.0),
            10.0
        );
    }

    /// The hostile inputs of issue 15 (each overflowed the stack before): refused with a
    /// message, never a crash; the limits are those of [`crate::limits`].
    #[test]
    fn hostile_nesting_is_refused_not_overflowed() {
        let hostile = [
            format!("{}1{}", "(".repeat(7000), ")".repeat(7000)),
            vec!["2"; 20_000].join("^"),
            format!("{}1", "-".repeat(65_000)),
            vec!["1"; 87_000].join("+"),
            // within the length limit, beyond the depth limit
            format!("{}1{}", "(".repeat(1000), ")".repeat(1000)),
            format!("{}1", "-".repeat(2000)),
            vec!["1"; 2000].join("+"),
            vec!["2"; 1000].join("^"),
            format!("{}1{}", "sin(".repeat(500), ")".repeat(500)),
        ];
        for text in &hostile {
            let msg = Expr::parse(text).unwrap_err().to_string();
            assert!(
                msg.contains("at most") || msg.contains("deeper than"),
                "{msg}"
            );
            assert!(msg.len() < 300, "one short line: {} bytes", msg.len());
        }
    }

    /// Constant subtrees are folded at parse time without changing a bit of the result: the
    /// laser source of the bundled `laser_film` case evaluates exactly as written in Rust.
    #[test]
    fn constant_subtrees_fold_to_the_same_bits() {
        let e = Expr::parse(
            "0.94*13.4*(1 - 0.93)/(100e-15*15.3e-9)*exp(-x/15.3e-9 - 1.992*abs(t - 200e-15)/100e-15)",
        )
        .unwrap();
        // the first factor is one number now: Mul(Num, exp(..))
        let Node::Bin(Op::Mul, a, _) = &e.root else {
            panic!("{:?}", e.root)
        };
        assert!(matches!(**a, Node::Num(_)), "{a:?}");
        for (x, t) in [(0.0, 0.0), (3e-9, 1.7e-13), (2e-8, 1e-12)] {
            let direct = 0.94 * 13.4 * (1.0 - 0.93) / (100e-15 * 15.3e-9)
                * (-x / 15.3e-9 - 1.992 * f64::abs(t - 200e-15) / 100e-15).exp();
            assert_eq!(e.eval(x, 0.0, 0.0, t).to_bits(), direct.to_bits());
        }
        assert_eq!(
            Expr::parse("2*pi").unwrap().eval(5.0, 0.0, 0.0, 0.0),
            2.0 * PI
        );
    }

    /// The deepest accepted tree evaluates on a thread with a small (256 kB) stack.
    #[test]
    fn the_deepest_accepted_expression_evaluates_on_a_small_stack() {
        let n = MAX_EXPR_DEPTH / 2 - 2;
        let text = format!("{}1{}", "(1+".repeat(n), ")".repeat(n));
        let e = Expr::parse(&text).unwrap();
        let v = std::thread::Builder::new()
            .stack_size(256 * 1024)
            .spawn(move || e.eval(0.0, 0.0, 0.0, 0.0))
            .unwrap()
            .join()
            .unwrap();
        assert_eq!(v, (n + 1) as f64);
    }

    #[test]
    fn errors_name_the_problem() {
        for bad in ["5*", "foo(1)", "exp 2", "(1", "1 $ 2", "min(1)"] {
            let msg = Expr::parse(bad).unwrap_err().to_string();
            assert!(msg.contains(bad), "{msg}");
        }
    }
}
