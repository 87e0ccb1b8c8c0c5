//! Front-end timing on the Freeman sky (seed 000): preprocess + parse, and check, measured
//! side by side in one criterion run.

use criterion::{Criterion, criterion_group, criterion_main};
use gdshader::{SourceDb, parse, preprocess};
use std::hint::black_box;

const FREEMAN: &str = include_str!("../../../fixtures/freeman_sky.gdshader");

/// An include loader for a shader that has none.
struct NoIncludes;

impl preprocess::Loader for NoIncludes {
    fn load(&mut self, path: &std::path::Path) -> std::io::Result<Vec<u8>> {
        Err(std::io::Error::new(std::io::ErrorKind::NotFound, path.display().to_string()))
    }
}

fn preprocess_only(text: &str) -> preprocess::Preprocessed {
    let mut db = SourceDb::new();
    let root = db.add("freeman_sky.gdshader", text.to_string(), None);
    let mut diags = Vec::new();
    let pre = preprocess::preprocess(&mut db, root, &mut NoIncludes, &mut diags);
    assert!(diags.is_empty());
    pre
}

fn preprocess_and_parse(text: &str) -> parse::ast::Shader {
    let mut db = SourceDb::new();
    let root = db.add("freeman_sky.gdshader", text.to_string(), None);
    let mut diags = Vec::new();
    let pre = preprocess::preprocess(&mut db, root, &mut NoIncludes, &mut diags);
    let (ast, parse_diags) = parse::parse(&pre.text);
    assert!(diags.is_empty() && parse_diags.is_empty());
    ast
}

fn frontend(c: &mut Criterion) {
    let mut group = c.benchmark_group("freeman_sky");
    group.bench_function("preprocess", |b| b.iter(|| preprocess_only(black_box(FREEMAN))));
    let text = preprocess_only(FREEMAN).text;
    group.bench_function("parse", |b| b.iter(|| parse::parse(black_box(&text))));
    group.bench_function("preprocess+parse", |b| b.iter(|| preprocess_and_parse(black_box(FREEMAN))));
    let ast = preprocess_and_parse(FREEMAN);
    group.bench_function("check", |b| {
        b.iter_batched(|| ast.clone(), |ast| gdshader::check::check(black_box(ast)), criterion::BatchSize::SmallInput)
    });
    group.bench_function("all (check_source)", |b| {
        b.iter(|| {
            gdshader::check_source(
                "freeman_sky.gdshader",
                black_box(FREEMAN.as_bytes().to_vec()),
                None,
                &mut NoIncludes,
            )
        })
    });
    group.finish();
}

criterion_group!(benches, frontend);
criterion_main!(benches);
