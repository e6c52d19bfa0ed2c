//! Webots' JavaScript PROTO templates (`# template language: javascript`), evaluated in a
//! sandbox: one job, from a PROTO's content scope and its field values to the VRML text the
//! template generates.
//!
//! The engine is QuickJS (through `rquickjs`): a small C engine with a memory limit and an
//! interrupt hook built in. The sandbox holds what Webots documents for templates and nothing
//! that reaches outside the process or the clock:
//! - `fields.NAME.value` / `.defaultValue` and `context`, as the caller gives them;
//! - the modules `wbrandom.js`, `wbvector2.js`, `wbvector3.js`, `wbrotation.js`,
//!   `wbgeometry.js`, `wbutility.js` (regatta's own code, written from Webots' documentation
//!   of their functions), and no other import;
//! - no file, network or environment access (`wbfile`'s functions throw), a clock that stands
//!   still (`Date.now()` is a number derived from the caller's seed; local time is UTC), and a
//!   `Math.random` seeded from the same number;
//! - `Math`'s transcendental functions computed by the `libm` crate, so that generated
//!   geometry is the same on every platform;
//! - a work limit counted in the engine's own steps, not in seconds, so that a template passes
//!   or fails the same way on any machine; and a memory limit.
//!
//! A world with no template never creates an [`Engine`].

mod compose;

pub use compose::Block;

/// The template blocks (`%< … >%`, `%<= … >%`) of a PROTO's content scope, in order, as the
/// composition reads them (`#` comments hide blocks, strings hold them); `Err` with the
/// offset of a block that is never closed.
pub fn blocks(content: &str) -> Result<Vec<Block>, usize> {
    compose::blocks(content).map_err(|unclosed| unclosed.start)
}

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};

use rquickjs::loader::{ImportAttributes, Loader, Resolver};
use rquickjs::module::Declared;
use rquickjs::{CatchResultExt, CaughtError, Context, Ctx, Function, Module, Object, Runtime};

/// The modules a template may import, by the name Webots gives them.
pub const MODULES: &[(&str, &str)] = &[
    ("wbgeometry.js", include_str!("../js/wbgeometry.js")),
    ("wbrandom.js", include_str!("../js/wbrandom.js")),
    ("wbrotation.js", include_str!("../js/wbrotation.js")),
    ("wbutility.js", include_str!("../js/wbutility.js")),
    ("wbvector2.js", include_str!("../js/wbvector2.js")),
    ("wbvector3.js", include_str!("../js/wbvector3.js")),
];

const PRELUDE: &str = include_str!("../js/prelude.js");

const THREW_NULL: &str = "the template threw null";

/// How much a template may use.
#[derive(Clone, Copy, Debug)]
pub struct Limits {
    /// Bytes of JavaScript heap.
    pub memory: usize,
    /// Work, in the engine's interrupt checks (one about every 10,000 calls and backward
    /// jumps): independent of the machine's speed.
    pub work: u64,
    /// Bytes of native stack for JavaScript recursion.
    pub stack: usize,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            memory: 64 << 20,
            // About 2·10⁸ calls and loop iterations: a second or two of work.
            work: 20_000,
            stack: 512 << 10,
        }
    }
}

/// One template to expand.
#[derive(Clone, Debug)]
pub struct Request<'a> {
    /// The PROTO's content scope: the text between the braces of its body.
    pub content: &'a str,
    /// The name errors and stack traces give the template (the PROTO's file).
    pub name: &'a str,
    /// `{ NAME: { value, defaultValue }, … }` in Webots' JavaScript shapes.
    pub fields: &'a serde_json::Value,
    /// Webots' `context` object.
    pub context: &'a serde_json::Value,
    /// Seeds `wbrandom`'s default state, `Math.random` and the standing clock.
    pub seed: u32,
}

/// What a template wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct Generated {
    /// The VRML text of the PROTO's content scope.
    pub text: String,
    /// What it printed with `console.*`, in order.
    pub console: Vec<ConsoleLine>,
}

/// A line a template printed.
#[derive(Clone, Debug, PartialEq)]
pub struct ConsoleLine {
    /// True for `console.warn` and `console.error`.
    pub warning: bool,
    pub text: String,
}

/// A template that could not be expanded.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{message}")]
pub struct TemplateError {
    pub message: String,
    /// Byte offset in [`Request::content`] where it went wrong, when known.
    pub offset: Option<usize>,
}

impl TemplateError {
    fn at(message: impl Into<String>, offset: Option<usize>) -> TemplateError {
        TemplateError {
            message: message.into(),
            offset,
        }
    }
}

/// A JavaScript runtime for templates: created once for a check, when the first template
/// needs it; every expansion gets a fresh context (no state leaks from one to the next).
pub struct Engine {
    runtime: Runtime,
    limits: Limits,
    work: Arc<AtomicU64>,
    refused_imports: Arc<Mutex<Vec<String>>>,
}

impl std::fmt::Debug for Engine {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Engine")
            .field("limits", &self.limits)
            .finish()
    }
}

/// Serves the built-in modules and refuses every other import.
struct Modules {
    refused: Arc<Mutex<Vec<String>>>,
}

impl Resolver for Modules {
    fn resolve<'js>(
        &mut self,
        _ctx: &Ctx<'js>,
        base: &str,
        name: &str,
        _attributes: Option<ImportAttributes<'js>>,
    ) -> rquickjs::Result<String> {
        if MODULES.iter().any(|(n, _)| *n == name) {
            Ok(name.to_owned())
        } else {
            if let Ok(mut refused) = self.refused.lock() {
                refused.push(name.to_owned());
            }
            Err(rquickjs::Error::new_resolving(base, name))
        }
    }
}

impl Loader for Modules {
    fn load<'js>(
        &mut self,
        ctx: &Ctx<'js>,
        name: &str,
        _attributes: Option<ImportAttributes<'js>>,
    ) -> rquickjs::Result<Module<'js, Declared>> {
        let (_, source) = MODULES
            .iter()
            .find(|(n, _)| *n == name)
            .ok_or_else(|| rquickjs::Error::new_loading(name))?;
        Module::declare(ctx.clone(), name, *source)
    }
}

impl Engine {
    /// A runtime with `limits`.
    pub fn new(limits: Limits) -> Result<Engine, TemplateError> {
        let runtime = Runtime::new().map_err(|e| {
            TemplateError::at(format!("cannot start the JavaScript engine: {e}"), None)
        })?;
        runtime.set_memory_limit(limits.memory);
        runtime.set_max_stack_size(limits.stack);
        let work = Arc::new(AtomicU64::new(0));
        let counter = work.clone();
        let budget = limits.work;
        runtime.set_interrupt_handler(Some(Box::new(move || {
            counter.fetch_add(1, Ordering::Relaxed) >= budget
        })));
        let refused_imports = Arc::new(Mutex::new(Vec::new()));
        runtime.set_loader(
            Modules {
                refused: refused_imports.clone(),
            },
            Modules {
                refused: refused_imports.clone(),
            },
        );
        Ok(Engine {
            runtime,
            limits,
            work,
            refused_imports,
        })
    }

    /// Expands one template.
    pub fn expand(&self, request: &Request<'_>) -> Result<Generated, TemplateError> {
        let composed = compose::compose(request.content).map_err(|unclosed| {
            TemplateError::at(
                "this template block is never closed with '>%'",
                Some(unclosed.start),
            )
        })?;
        self.work.store(0, Ordering::Relaxed);
        if let Ok(mut refused) = self.refused_imports.lock() {
            refused.clear();
        }
        let context = Context::full(&self.runtime).map_err(|e| {
            TemplateError::at(format!("cannot start the JavaScript engine: {e}"), None)
        })?;
        let result = context.with(|ctx| -> Result<Generated, TemplateError> {
            self.install(&ctx, request)
                .map_err(|e| TemplateError::at(format!("template set-up failed: {e}"), None))?;
            let evaluated = Module::evaluate(ctx.clone(), request.name, composed.js.as_bytes())
                .and_then(|promise| promise.finish::<()>())
                .catch(&ctx);
            if let Err(caught) = evaluated {
                return Err(self.explain(caught, request, &composed));
            }
            let globals = ctx.globals();
            let text: String = globals
                .get(compose::OUT)
                .map_err(|e| TemplateError::at(format!("the template wrote no text: {e}"), None))?;
            let console: Vec<(bool, String)> = globals
                .get::<_, rquickjs::Value>("__regatta_console")
                .ok()
                .and_then(|v| v.into_array())
                .map(|lines| {
                    lines
                        .iter::<Vec<rquickjs::Value>>()
                        .filter_map(|line| {
                            let line = line.ok()?;
                            let warning = line.first()?.as_bool()?;
                            let text = line.get(1)?.as_string()?.to_string().ok()?;
                            Some((warning, text))
                        })
                        .collect()
                })
                .unwrap_or_default();
            Ok(Generated {
                text,
                console: console
                    .into_iter()
                    .map(|(warning, text)| ConsoleLine { warning, text })
                    .collect(),
            })
        });
        let result = match result {
            Err(error)
                if error.message == THREW_NULL
                    && self.runtime.memory_usage().malloc_size as usize
                        > self.limits.memory / 2 =>
            {
                Err(self.out_of_memory())
            }
            other => other,
        };
        drop(context);
        self.runtime.run_gc();
        result
    }

    fn out_of_memory(&self) -> TemplateError {
        TemplateError::at(
            format!(
                "the template ran out of memory (limit {} MiB)",
                self.limits.memory >> 20
            ),
            None,
        )
    }

    /// Globals: `fields`, `context`, the prelude (clock, randomness, console, wbfile) and
    /// `Math`'s transcendental functions from `libm`.
    fn install<'js>(&self, ctx: &Ctx<'js>, request: &Request<'_>) -> rquickjs::Result<()> {
        let globals = ctx.globals();
        let json = |value: &serde_json::Value| ctx.json_parse(value.to_string());
        globals.set("fields", json(request.fields)?)?;
        globals.set("context", json(request.context)?)?;
        let libm = Object::new(ctx.clone())?;
        macro_rules! unary {
            ($($name:ident),*) => {$(
                libm.set(stringify!($name), Function::new(ctx.clone(), |x: f64| libm::$name(x))?)?;
            )*};
        }
        unary!(
            sin, cos, tan, asin, acos, atan, sinh, cosh, tanh, asinh, acosh, atanh, exp, expm1,
            log, log1p, log2, log10, cbrt
        );
        libm.set(
            "atan2",
            Function::new(ctx.clone(), |y: f64, x: f64| libm::atan2(y, x))?,
        )?;
        libm.set(
            "pow",
            Function::new(ctx.clone(), |x: f64, y: f64| libm::pow(x, y))?,
        )?;
        globals.set("__regatta_libm", libm)?;
        globals.set("__regatta_seed", request.seed)?;
        ctx.eval::<(), _>(PRELUDE)?;
        Ok(())
    }

    /// The error a failed evaluation reports, placed in the template where possible.
    fn explain(
        &self,
        caught: CaughtError<'_>,
        request: &Request<'_>,
        composed: &compose::Composed,
    ) -> TemplateError {
        if self.work.load(Ordering::Relaxed) >= self.limits.work {
            let offset = match &caught {
                CaughtError::Exception(exception) => exception
                    .stack()
                    .and_then(|stack| frame_in(&stack, request.name))
                    .and_then(|(line, column)| composed.offset_of(line, column))
                    .and_then(|at| composed.content_offset(at)),
                _ => None,
            };
            return TemplateError::at(
                format!(
                    "the template ran past its work limit (about {} million steps): an endless loop?",
                    self.limits.work / 100
                ),
                offset,
            );
        }
        let refused = self
            .refused_imports
            .lock()
            .map(|r| r.first().cloned())
            .unwrap_or_default();
        if let Some(name) = refused {
            let offset = request
                .content
                .find(&format!("'{name}'"))
                .or_else(|| request.content.find(&format!("\"{name}\"")));
            let available: Vec<&str> = MODULES.iter().map(|(n, _)| *n).collect();
            return TemplateError::at(
                format!(
                    "cannot import '{name}': templates read no files; regatta provides {}",
                    available.join(", ")
                ),
                offset,
            );
        }
        let out_of_memory = || self.out_of_memory();
        match caught {
            // QuickJS throws null when it cannot even allocate the error; the caller tells
            // that from a template's own `throw null` by the memory in use.
            CaughtError::Value(value) if value.is_null() => TemplateError::at(THREW_NULL, None),
            CaughtError::Exception(exception) => {
                let message = exception.message().unwrap_or_default();
                let kind: Option<String> = exception
                    .as_object()
                    .get::<_, Object>("constructor")
                    .and_then(|c| c.get::<_, String>("name"))
                    .ok();
                let line: Option<usize> = exception.as_object().get("lineNumber").ok();
                let column: Option<usize> = exception.as_object().get("columnNumber").ok();
                let from_stack = exception
                    .stack()
                    .and_then(|stack| frame_in(&stack, request.name));
                let place = match (line, column) {
                    (Some(line), Some(column)) if line > 0 => Some((line, column)),
                    _ => from_stack,
                };
                let offset = place
                    .and_then(|(line, column)| composed.offset_of(line, column))
                    .and_then(|at| composed.content_offset(at));
                let kind = kind.unwrap_or_else(|| "Error".to_owned());
                if message.contains("out of memory") {
                    return out_of_memory();
                }
                TemplateError::at(format!("{kind}: {message}"), offset)
            }
            CaughtError::Value(value) => {
                let text = value
                    .as_string()
                    .and_then(|s| s.to_string().ok())
                    .or_else(|| value.as_number().map(|n| n.to_string()))
                    .unwrap_or_else(|| format!("a {}", value.type_name()));
                TemplateError::at(format!("the template threw {text}"), None)
            }
            CaughtError::Error(error) => {
                let text = error.to_string();
                if text.contains("out of memory") || text.contains("Allocation") {
                    out_of_memory()
                } else {
                    TemplateError::at(text, None)
                }
            }
        }
    }
}

/// Line and column of the first stack frame in the template's own module.
fn frame_in(stack: &str, name: &str) -> Option<(usize, usize)> {
    stack.lines().find_map(|frame| {
        let at = frame.find(name)? + name.len();
        let mut numbers = frame[at..]
            .trim_start_matches(':')
            .split(|c: char| !c.is_ascii_digit())
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<usize>().ok());
        let line = numbers.next()??;
        let column = numbers.next().flatten().unwrap_or(1);
        Some((line, column))
    })
}
