//! Reports' prose as Markdown templates (`templates/`, rendered by minijinja): Rust computes the
//! numbers, tables and figures and passes them in by name; the words live in the templates.
//!
//! Filters for numbers (NaN or a missing value prints "–"):
//! `f(n)` fixed with n decimals, `signed(n)` with its sign, `sci(n)` as 4.80e5, `g(n)` n significant
//! figures, fixed between 0.01 and 1e4 and scientific outside, `pm(n)` an
//! estimate `{mean, ci95}` as "mean ± ci95", `spm(n)` the same signed, `int` with thin thousands.

use minijinja::value::{Kwargs, Value};
use minijinja::{Environment, Error as JinjaError, ErrorKind, UndefinedBehavior};
use serde::Serialize;

/// Every template, by name (its path under `templates/`), embedded in the binary.
macro_rules! templates {
    ($($name:literal),* $(,)?) => { &[$(($name, include_str!(concat!("../../templates/", $name)))),*] };
}
pub const TEMPLATES: &[(&str, &str)] = templates![
    "paper/README.md",
    "paper/appendix-a-case1.md",
    "paper/appendix-b-why.md",
    "paper/appendix-c-finite-size.md",
    "paper/appendix-d-magnetisation.md",
    "paper/appendix-e-case2.md",
    "paper/appendix-f-engines.md",
    "paper/appendix-g-runs.md",
    "paper/sections/provenance.md",
    "paper/sections/runs.md",
    "paper/sections/engines.md",
    "paper/sections/table4.md",
    "paper/sections/boxplots.md",
    "paper/sections/chains.md",
    "paper/sections/paraview.md",
    "paper/sections/approach.md",
    "paper/sections/seeds.md",
    "paper/sections/finite_size.md",
    "paper/sections/box_count.md",
    "paper/sections/growth.md",
    "paper/sections/magnetisation.md",
    "paper/sections/measurement.md",
    "paper/sections/table3.md",
    "paper/sections/sensitivity.md",
    "paper/sections/ranking.md",
    "paper/sections/shielding.md",
    "paper/sections/case2.md",
    "paper/sections/reynolds.md",
    "accuracy/README.md",
    "accuracy/stability.md",
    "verification/contacts.md",
    "verification/magnetic.md",
    "hydrodynamics/README.md",
    "hydrodynamics/macros.md",
    "performance/README.md",
];

type Error = Box<dyn std::error::Error>;

fn number(v: &Value) -> Option<f64> {
    f64::try_from(v.clone()).ok().filter(|x| x.is_finite())
}

fn fixed(v: Value, digits: Option<usize>) -> String {
    number(&v).map_or("–".into(), |x| format!("{:.*}", digits.unwrap_or(1), x))
}

fn signed(v: Value, digits: Option<usize>) -> String {
    number(&v).map_or("–".into(), |x| format!("{:+.*}", digits.unwrap_or(1), x).replace('-', "−"))
}

/// Fixed with `digits` significant figures between 0.01 and 1e4, else scientific.
fn general(v: Value, digits: Option<usize>) -> String {
    let digits = digits.unwrap_or(2);
    match number(&v) {
        Some(x) if x == 0.0 || (1e-2..1e4).contains(&x.abs()) => {
            let decimals = (digits as i32 - 1 - x.abs().log10().floor() as i32).max(0) as usize;
            format!("{x:.decimals$}").replace('-', "−")
        }
        Some(_) => sci(v, Some(digits.saturating_sub(1))),
        None => "–".into(),
    }
}

fn sci(v: Value, digits: Option<usize>) -> String {
    number(&v).map_or("–".into(), |x| format!("{:.*e}", digits.unwrap_or(2), x).replace('-', "−"))
}

/// `{mean, ci95}` as "mean ± ci95" ("mean" alone when the CI is not finite).
fn estimate(v: &Value, digits: usize, with_sign: bool) -> Result<String, JinjaError> {
    let field = |k: &str| v.get_attr(k).ok().and_then(|x| number(&x));
    let Some(mean) = field("mean") else { return Ok("–".into()) };
    let m = if with_sign { format!("{mean:+.digits$}").replace('-', "−") } else { format!("{mean:.digits$}") };
    Ok(match field("ci95") {
        Some(ci) => format!("{m} ± {ci:.digits$}"),
        None => m,
    })
}

fn int(v: Value) -> String {
    let Some(x) = number(&v) else { return "–".into() };
    let digits = format!("{:.0}", x.abs());
    let mut out = String::new();
    for (k, ch) in digits.chars().enumerate() {
        if k > 0 && (digits.len() - k) % 3 == 0 && digits.len() > 4 {
            out.push('\u{202f}');
        }
        out.push(ch);
    }
    if x < 0.0 {
        format!("−{out}")
    } else {
        out
    }
}

/// The environment with every template and filter; undefined names are errors.
pub fn environment() -> Environment<'static> {
    let mut env = Environment::new();
    env.set_undefined_behavior(UndefinedBehavior::Strict);
    env.set_trim_blocks(true);
    env.set_lstrip_blocks(true);
    env.set_keep_trailing_newline(true);
    for (name, text) in TEMPLATES {
        env.add_template(name, text).expect("templates parse (checked by tests/templates.rs)");
    }
    env.add_filter("f", fixed);
    env.add_filter("signed", signed);
    env.add_filter("sci", sci);
    env.add_filter("g", general);
    env.add_filter("int", int);
    env.add_filter("pm", |v: Value, d: Option<usize>| estimate(&v, d.unwrap_or(1), false));
    env.add_filter("spm", |v: Value, d: Option<usize>| estimate(&v, d.unwrap_or(1), true));
    env.add_filter("join_and", |v: Value, kw: Kwargs| -> Result<String, JinjaError> {
        let items: Vec<String> = v.try_iter()?.map(|x| x.to_string()).collect();
        kw.assert_all_used()?;
        Ok(match items.len() {
            0 => String::new(),
            1 => items[0].clone(),
            n => format!("{} and {}", items[..n - 1].join(", "), items[n - 1]),
        })
    });
    env
}

/// Renders template `name` with `context`.
pub fn render(name: &str, context: &impl Serialize) -> Result<String, Error> {
    let env = environment();
    let template = env.get_template(name)?;
    template.render(Value::from_serialize(context)).map_err(|e| {
        let mut msg = format!("template {name}: {e}");
        let mut source = std::error::Error::source(&e);
        while let Some(s) = source {
            msg += &format!(": {s}");
            source = s.source();
        }
        Box::new(JinjaError::new(ErrorKind::InvalidOperation, msg)) as Error
    })
}
