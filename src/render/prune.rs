//! Drops the code a kernel's constants rule out (`if (FEATURE_CUTOUT && …)` in a kernel
//! without cut-outs) from its naga module, before the driver sees it.
//!
//! Drivers do remove such branches, but Mesa inlines every call first: the material
//! graphs behind a false `FEATURE_CUTOUT`, or a second `transmittance` behind a false
//! `FEATURE_SHADOW_CATCHER`, were compiled by LLVM and then thrown away, a third of the
//! showcase's kernel build (docs/BENCHMARKS.md). Here a branch whose condition is a
//! constant is replaced by the block it takes, statements after a `return`, `break` or
//! `continue` go, and [`naga::compact`] drops the functions and expressions nothing uses
//! any more.
//!
//! WGSL's `&&` and `||` reach naga as an `if` that stores into a nameless local, which
//! the branch then loads (`var t; if (a) { t = b; } else { t = false; } if (t) { … }`).
//! A load that follows the local's only store, in the same block or one nested in it,
//! takes the stored constant; so `FEATURE_X && runtime_test` folds too. And a function
//! pruned down to `return <constant>` (`principled_is_diffuse` in a kernel with the
//! diffuse lobe alone) is that constant at its calls, so the branches on it fold.

use std::collections::HashMap;

use naga::{
    BinaryOperator, Block, Expression, Function, Handle, Literal, LocalVariable, Module, Statement,
    UnaryOperator,
};

/// What [`prune`] removed from a module.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Pruned {
    /// Branches (`if`s) replaced by the one block they take.
    pub branches: usize,
    /// Function calls in the code removed (each would have been inlined).
    pub calls: usize,
    /// Functions no call reaches any more, dropped from the module.
    pub functions: usize,
}

/// Removes what `module`'s constants rule out; the module stays valid and computes
/// the same (the removed code could never run).
pub fn prune(module: &mut Module) -> Pruned {
    let constants = module
        .constants
        .iter()
        .filter_map(|(handle, constant)| Some((handle, global_value(module, constant.init)?)))
        .collect();
    let results: HashMap<_, _> = module
        .functions
        .iter()
        .filter_map(|(handle, function)| Some((handle, function.result.as_ref()?.ty)))
        .collect();
    let mut pruned = Pruned::default();
    // naga orders functions callee first, so a function is pruned before its callers
    // ask whether it returns a constant.
    let mut constant_functions = HashMap::new();
    let functions = module
        .functions
        .iter_mut()
        .map(|(h, function)| (Some(h), function));
    let entry_points = module
        .entry_points
        .iter_mut()
        .map(|entry| (None, &mut entry.function));
    for (handle, function) in functions.chain(entry_points) {
        let mut pass = FunctionPass {
            constants: &constants,
            results: &results,
            constant_functions: &constant_functions,
            function,
        };
        pass.run(&mut pruned);
        if let (Some(handle), Some(value)) = (handle, pass.constant_result()) {
            constant_functions.insert(handle, value);
        }
    }
    if pruned != Pruned::default() {
        let before = module.functions.len();
        naga::compact::compact(module, naga::compact::KeepUnused::No);
        pruned.functions = before - module.functions.len();
    }
    pruned
}

/// The value of a module-scope constant expression that is a literal, a constant or a
/// logical or comparison operator on them.
fn global_value(module: &Module, expr: Handle<Expression>) -> Option<Literal> {
    match module.global_expressions[expr] {
        Expression::Literal(literal) => Some(literal),
        Expression::Constant(constant) => global_value(module, module.constants[constant].init),
        Expression::Unary { op, expr } => unary(op, global_value(module, expr)?),
        Expression::Binary { op, left, right } => binary(
            op,
            global_value(module, left)?,
            global_value(module, right)?,
        ),
        _ => None,
    }
}

fn unary(op: UnaryOperator, value: Literal) -> Option<Literal> {
    match (op, value) {
        (UnaryOperator::LogicalNot, Literal::Bool(b)) => Some(Literal::Bool(!b)),
        _ => None,
    }
}

fn binary(op: BinaryOperator, left: Literal, right: Literal) -> Option<Literal> {
    let value = match (op, left, right) {
        (BinaryOperator::LogicalAnd, Literal::Bool(a), Literal::Bool(b)) => a && b,
        (BinaryOperator::LogicalOr, Literal::Bool(a), Literal::Bool(b)) => a || b,
        // Literals of the same type are equal exactly when their bits are (floats aside,
        // which the comparison below leaves out).
        (BinaryOperator::Equal, a, b) if comparable(a, b) => a == b,
        (BinaryOperator::NotEqual, a, b) if comparable(a, b) => a != b,
        _ => return None,
    };
    Some(Literal::Bool(value))
}

fn comparable(a: Literal, b: Literal) -> bool {
    matches!(
        (a, b),
        (Literal::Bool(_), Literal::Bool(_))
            | (Literal::U32(_), Literal::U32(_))
            | (Literal::I32(_), Literal::I32(_))
    )
}

struct FunctionPass<'a> {
    constants: &'a HashMap<Handle<naga::Constant>, Literal>,
    results: &'a HashMap<Handle<Function>, Handle<naga::Type>>,
    /// Functions already pruned to `return <constant>` with nothing else to do.
    constant_functions: &'a HashMap<Handle<Function>, Literal>,
    function: &'a mut Function,
}

impl FunctionPass<'_> {
    fn run(&mut self, pruned: &mut Pruned) {
        let start = *pruned;
        // Each round folds what the previous one made constant (`a && b && c` is a chain
        // of locals, each stored in both branches of the `if` before).
        loop {
            let stores = self.nameless_local_stores();
            let mut body = std::mem::take(&mut self.function.body);
            let before = *pruned;
            self.block(&mut body, &stores, &mut Vec::new(), pruned);
            self.function.body = body;
            if *pruned == before {
                break;
            }
        }
        if *pruned != start {
            self.settle();
        }
    }

    /// How many stores each nameless local has (and `None` for those something other
    /// than a store or a load uses: a call's argument, an access).
    fn nameless_local_stores(&self) -> HashMap<Handle<LocalVariable>, Option<usize>> {
        let function = &*self.function;
        let mut stores: HashMap<_, _> = function
            .local_variables
            .iter()
            .filter(|(_, local)| local.name.is_none() && local.init.is_none())
            .map(|(handle, _)| (handle, Some(0)))
            .collect();
        for (_, expr) in function.expressions.iter() {
            let (Expression::Access { base: pointer, .. }
            | Expression::AccessIndex { base: pointer, .. }) = *expr
            else {
                continue;
            };
            if let Expression::LocalVariable(local) = function.expressions[pointer] {
                stores.insert(local, None);
            }
        }
        visit(&function.body, &mut |statement| match *statement {
            Statement::Store { pointer, .. } => {
                if let Expression::LocalVariable(local) = function.expressions[pointer]
                    && let Some(Some(count)) = stores.get_mut(&local)
                {
                    *count += 1;
                }
            }
            Statement::Call { ref arguments, .. } => {
                for &argument in arguments {
                    if let Expression::LocalVariable(local) = function.expressions[argument] {
                        stores.insert(local, None);
                    }
                }
            }
            _ => {}
        });
        stores
    }

    /// The constant the function returns when all it does is return one: its body, once
    /// pruned, is emits and stores into its own locals (which its return discards), then
    /// `return <constant>`.
    fn constant_result(&self) -> Option<Literal> {
        let (last, rest) = self.function.body.split_last()?;
        let Statement::Return { value: Some(value) } = *last else {
            return None;
        };
        let idle = rest.iter().all(|statement| match *statement {
            Statement::Emit(_) => true,
            Statement::Store { pointer, .. } => matches!(
                self.function.expressions[pointer],
                Expression::LocalVariable(_)
            ),
            _ => false,
        });
        if idle { self.value(value) } else { None }
    }

    fn value(&self, expr: Handle<Expression>) -> Option<Literal> {
        match self.function.expressions[expr] {
            Expression::Literal(literal) => Some(literal),
            Expression::Constant(constant) => self.constants.get(&constant).copied(),
            Expression::Unary { op, expr } => unary(op, self.value(expr)?),
            Expression::Binary { op, left, right } => {
                binary(op, self.value(left)?, self.value(right)?)
            }
            _ => None,
        }
    }

    /// Prunes `block` in place. `known`: the nameless locals whose only store came
    /// before, with the constant it stored (a scope: what a block adds goes at its end).
    fn block(
        &mut self,
        block: &mut Block,
        stores: &HashMap<Handle<LocalVariable>, Option<usize>>,
        known: &mut Vec<(Handle<LocalVariable>, Literal)>,
        pruned: &mut Pruned,
    ) {
        let scope = known.len();
        let original = std::mem::replace(block, Block::with_capacity(block.len()));
        let mut statements: std::collections::VecDeque<_> = original.span_into_iter().collect();
        while let Some((mut statement, span)) = statements.pop_front() {
            match statement {
                Statement::If {
                    condition,
                    ref mut accept,
                    ref mut reject,
                } => {
                    if let Some(Literal::Bool(taken)) = self.value(condition) {
                        let (taken, dropped) = if taken {
                            (accept, reject)
                        } else {
                            (reject, accept)
                        };
                        pruned.branches += 1;
                        pruned.calls += dropped.iter().map(calls_in).sum::<usize>();
                        // The block taken goes in place of the `if`, its statements
                        // next in line.
                        let taken = std::mem::take(taken);
                        let taken: Vec<_> = taken.span_into_iter().collect();
                        for item in taken.into_iter().rev() {
                            statements.push_front(item);
                        }
                        continue;
                    }
                }
                Statement::Emit(ref range) => {
                    // A load of a known local becomes the constant it loads.
                    for expr in range.clone() {
                        let Expression::Load { pointer } = self.function.expressions[expr] else {
                            continue;
                        };
                        let Expression::LocalVariable(local) = self.function.expressions[pointer]
                        else {
                            continue;
                        };
                        if let Some(&(_, literal)) = known.iter().find(|(l, _)| *l == local) {
                            self.function.expressions[expr] = Expression::Literal(literal);
                        }
                    }
                }
                Statement::Call {
                    function,
                    result: Some(result),
                    ..
                } if self.constant_functions.contains_key(&function) => {
                    // A call that only returns a constant is the constant.
                    self.function.expressions[result] =
                        Expression::Literal(self.constant_functions[&function]);
                    pruned.calls += 1;
                    continue;
                }
                Statement::Store { pointer, value } => {
                    if let Expression::LocalVariable(local) = self.function.expressions[pointer]
                        && stores.get(&local) == Some(&Some(1))
                        && let Some(literal) = self.value(value)
                    {
                        known.push((local, literal));
                    }
                }
                _ => {}
            }
            // Each nested block is its own scope: a loop's continuing block too, since a
            // `continue` may skip the body's store.
            for nested in nested_blocks_mut(&mut statement) {
                self.block(nested, stores, known, pruned);
            }
            let ends = matches!(
                statement,
                Statement::Return { .. } | Statement::Kill | Statement::Break | Statement::Continue
            );
            block.push(statement, span);
            if ends {
                // Nothing after it in this block can run.
                pruned.calls += statements
                    .drain(..)
                    .map(|(s, _)| calls_in(&s))
                    .sum::<usize>();
            }
        }
        known.truncate(scope);
    }

    /// Makes the function valid again: emits no longer cover the loads that became
    /// literals, and the results of calls removed become zero values (naga requires
    /// every call result to have its call).
    fn settle(&mut self) {
        filter_emits(&mut self.function.body, &self.function.expressions);
        let mut called = std::collections::HashSet::new();
        visit(&self.function.body, &mut |statement| match *statement {
            Statement::Call {
                result: Some(result),
                ..
            }
            | Statement::Atomic {
                result: Some(result),
                ..
            } => {
                called.insert(result);
            }
            _ => {}
        });
        for (handle, expr) in self.function.expressions.iter_mut() {
            let ty = match *expr {
                Expression::CallResult(function) => self.results[&function],
                Expression::AtomicResult { ty, .. } => ty,
                _ => continue,
            };
            if !called.contains(&handle) {
                *expr = Expression::ZeroValue(ty);
            }
        }
    }
}

/// Calls `f` on every statement of `block`, nested ones included.
fn visit(block: &Block, f: &mut impl FnMut(&Statement)) {
    for statement in block {
        visit_statement(statement, f);
    }
}

fn visit_statement(statement: &Statement, f: &mut impl FnMut(&Statement)) {
    f(statement);
    for nested in nested_blocks(statement) {
        visit(nested, f);
    }
}

/// The calls in `statement` and the blocks nested in it.
fn calls_in(statement: &Statement) -> usize {
    let mut calls = 0;
    visit_statement(statement, &mut |s| {
        if matches!(s, Statement::Call { .. }) {
            calls += 1;
        }
    });
    calls
}

/// The blocks nested directly in `statement`, in the order they can run.
fn nested_blocks(statement: &Statement) -> Vec<&Block> {
    match *statement {
        Statement::Block(ref inner) => vec![inner],
        Statement::If {
            ref accept,
            ref reject,
            ..
        } => vec![accept, reject],
        Statement::Switch { ref cases, .. } => cases.iter().map(|case| &case.body).collect(),
        Statement::Loop {
            ref body,
            ref continuing,
            ..
        } => vec![body, continuing],
        _ => Vec::new(),
    }
}

/// [`nested_blocks`], to change.
fn nested_blocks_mut(statement: &mut Statement) -> Vec<&mut Block> {
    match *statement {
        Statement::Block(ref mut inner) => vec![inner],
        Statement::If {
            ref mut accept,
            ref mut reject,
            ..
        } => vec![accept, reject],
        Statement::Switch { ref mut cases, .. } => {
            cases.iter_mut().map(|case| &mut case.body).collect()
        }
        Statement::Loop {
            ref mut body,
            ref mut continuing,
            ..
        } => vec![body, continuing],
        _ => Vec::new(),
    }
}

/// Splits emits around the expressions that need none (naga's validator rejects an
/// emit of a literal), as naga's own override processing does.
fn filter_emits(block: &mut Block, expressions: &naga::Arena<Expression>) {
    let original = std::mem::replace(block, Block::with_capacity(block.len()));
    for (mut statement, span) in original.span_into_iter() {
        match statement {
            Statement::Emit(range) => {
                let mut run: Option<(Handle<Expression>, Handle<Expression>)> = None;
                for expr in range {
                    if expressions[expr].needs_pre_emit() {
                        if let Some((first, last)) = run.take() {
                            block.push(
                                Statement::Emit(naga::Range::new_from_bounds(first, last)),
                                span,
                            );
                        }
                    } else {
                        run = Some(run.map_or((expr, expr), |(first, _)| (first, expr)));
                    }
                }
                if let Some((first, last)) = run {
                    block.push(
                        Statement::Emit(naga::Range::new_from_bounds(first, last)),
                        span,
                    );
                }
                continue;
            }
            _ => {
                for nested in nested_blocks_mut(&mut statement) {
                    filter_emits(nested, expressions);
                }
            }
        }
        block.push(statement, span);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::kernel::{path_tracing_kernel, validator};
    use crate::shader::{KernelFeatures, lobes};

    fn pruned(wgsl: &str) -> (Module, Pruned) {
        let mut module = naga::front::wgsl::parse_str(wgsl).unwrap();
        let pruned = prune(&mut module);
        if let Err(e) = validator().validate(&module) {
            panic!("the pruned module is invalid: {}", e.emit_to_string(wgsl));
        }
        (module, pruned)
    }

    /// The names of the functions left in `module`, sorted.
    fn functions(module: &Module) -> Vec<&str> {
        let mut names: Vec<_> = module
            .functions
            .iter()
            .filter_map(|(_, f)| f.name.as_deref())
            .collect();
        names.sort_unstable();
        names
    }

    fn has_function(module: &Module, name: &str) -> bool {
        functions(module).contains(&name)
    }

    const HEAVY: &str = "
        @group(0) @binding(0) var<storage, read_write> out: array<f32>;
        fn heavy(x: f32) -> f32 { return sin(x) * cos(x); }
        fn other(x: f32) -> f32 { return exp(x); }
        fn kept(x: f32) -> f32 { return sqrt(x); }
    ";

    #[test]
    fn a_false_constant_takes_its_calls_and_their_functions_with_it() {
        let wgsl = format!(
            "{HEAVY}
            const ON: bool = true;
            const OFF: bool = false;
            const MODE: u32 = 2u;
            @compute @workgroup_size(1) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
                var x = out[id.x];
                if (OFF && x > 0.0) {{ x = heavy(x); }}
                if (ON || x > 1.0) {{ x = kept(x); }}
                if (MODE == 3u) {{ x += other(x); }} else {{ x += 1.0; }}
                out[id.x] = x;
            }}"
        );
        let (module, pruned) = pruned(&wgsl);
        // heavy() only ran under OFF, other() only when MODE == 3; kept() runs whenever ON.
        assert_eq!(functions(&module), ["kept"]);
        assert_eq!(pruned.calls, 2);
    }

    #[test]
    fn an_early_return_under_a_true_constant_drops_the_rest() {
        let wgsl = format!(
            "{HEAVY}
            const SIMPLE: bool = true;
            const VOLUMES: bool = false;
            fn shade(x: f32) -> f32 {{
                if (SIMPLE && !VOLUMES) {{ return kept(x); }}
                return heavy(x) + other(x);
            }}
            @compute @workgroup_size(1) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
                out[id.x] = shade(out[id.x]);
            }}"
        );
        let (module, pruned) = pruned(&wgsl);
        assert_eq!(functions(&module), ["kept", "shade"]);
        assert_eq!(pruned.calls, 2);
    }

    #[test]
    fn a_call_that_only_returns_a_constant_is_the_constant() {
        // shaders/bsdf/principled.wgsl's `principled_is_diffuse` in a kernel with the
        // diffuse lobe alone.
        let wgsl = format!(
            "{HEAVY}
            const LAYERED: bool = false;
            fn matte(x: f32) -> bool {{
                if (!LAYERED && !LAYERED) {{ return true; }}
                return x > 0.0 && other(x) > 1.0;
            }}
            @compute @workgroup_size(1) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
                let u = out[id.x];
                if (matte(u)) {{ out[id.x] = kept(u); }} else {{ out[id.x] = heavy(u); }}
            }}"
        );
        let (module, pruned) = pruned(&wgsl);
        // matte()'s one call became `true`.
        assert_eq!(functions(&module), ["kept"]);
        // other() in matte's tail, matte() itself, heavy() in the branch not taken.
        assert_eq!(pruned.calls, 3);
    }

    #[test]
    fn runtime_tests_and_named_variables_stay() {
        // `t` is a variable the code names and stores twice; `u > 0.0` is known only
        // when the kernel runs. Nothing here may go.
        let wgsl = format!(
            "{HEAVY}
            const ON: bool = true;
            @compute @workgroup_size(1) fn main(@builtin(global_invocation_id) id: vec3<u32>) {{
                let u = out[id.x];
                var t = true;
                if (u > 0.0) {{ t = false; }}
                if (t) {{ out[id.x] = heavy(u); }}
                if (ON && u > 1.0) {{ out[id.x] = other(u); }}
                loop {{
                    if (ON || u > 2.0) {{ break; }}
                    out[id.x] = kept(u);
                }}
            }}"
        );
        let (module, pruned) = pruned(&wgsl);
        // heavy(): t may be true or false; other(): ON && u > 1.0 depends on u.
        assert_eq!(functions(&module), ["heavy", "other"]);
        // `true || u > 2.0` is true: the loop ends before kept(), the one call removed.
        assert_eq!(pruned.calls, 1);
    }

    #[test]
    fn every_specialised_path_kernel_prunes_to_a_valid_module() {
        let materials = crate::material::materials_wgsl(&[]);
        let everything = KernelFeatures::default();
        let mut variants = vec![everything];
        for (bit, _) in lobes::NAMES {
            variants.push(KernelFeatures {
                lobes: everything.lobes & !bit,
                ..everything
            });
        }
        let bare = KernelFeatures {
            lobes: lobes::DIFFUSE,
            environment_map: false,
            analytic_lights: false,
            shadow_catcher: false,
            textures: false,
            aovs: false,
            uv1: false,
            noise: false,
            ..everything
        };
        variants.push(bare);
        for ablation in crate::shader::Ablation::ALL {
            variants.push(KernelFeatures { ablation, ..bare });
        }
        // The kernel lavapipe runs: texel tables read as storage textures.
        variants.push(KernelFeatures {
            texel_reads: crate::shader::bindings::TexelReads::Storage,
            ..bare
        });
        for features in variants {
            let mut module = path_tracing_kernel(&features, &materials)
                .validate()
                .unwrap();
            prune(&mut module);
            if let Err(e) = validator().validate(&module) {
                panic!("{features:?}: the pruned kernel is invalid: {e:?}");
            }
            // The shadow catcher's light sample is called from one branch only.
            assert_eq!(
                has_function(&module, "catcher_shadow"),
                features.shadow_catcher && features.ablation == Default::default(),
                "{features:?}"
            );
        }
    }
}
