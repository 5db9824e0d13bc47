//! Unit tests of the front end over the bundled techniques.

use super::ast::PassKind;
use super::expr::{Expr, MAX_NODES, MAX_TREE_DEPTH};

/// The bundled techniques' expressions use at most an eighth of the depth limit and a
/// sixty-fourth of the node limit: the limits bound hostile input, not real techniques.
#[test]
fn bundled_techniques_are_far_below_the_expression_limits() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../techniques");
    let mut n = 0;
    for f in std::fs::read_dir(&dir).unwrap() {
        let p = f.unwrap().path();
        if p.extension().is_none_or(|x| x != "ron") {
            continue;
        }
        let src = std::fs::read_to_string(&p).unwrap();
        let t = super::parse::parse(&src).unwrap_or_else(|e| panic!("{}: {e:?}", p.display()));
        let mut exprs: Vec<&Expr> = Vec::new();
        for c in &t.channels {
            exprs.extend(c.value.as_ref());
        }
        for x in &t.expansions {
            exprs.extend([&x.from, &x.to, &x.constant]);
            exprs.extend(x.lets.iter().map(|l| &l.1));
            exprs.extend(x.terms.iter().flat_map(|t| [&t.coeff, &t.basis]));
        }
        for pass in &t.passes {
            if let PassKind::Shade { visibility, .. } = &pass.kind {
                exprs.push(visibility);
            }
        }
        for e in exprs {
            assert!(e.height() <= MAX_TREE_DEPTH / 8, "{}: depth {}", p.display(), e.height());
            assert!(e.size() <= MAX_NODES as usize / 64, "{}: {} nodes", p.display(), e.size());
        }
        n += 1;
    }
    assert!(n >= 5, "found {n} techniques");
}
