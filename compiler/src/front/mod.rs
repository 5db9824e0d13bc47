//! The front end: spanned RON, the expression language, and the technique AST.

pub mod ast;
pub mod expr;
pub mod parse;
pub mod ron;

#[cfg(test)]
mod tests;
