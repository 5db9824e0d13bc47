//! Cross-crate tests live in `tests/`. This library holds what they share: the
//! hand-written reference implementations of the bundled techniques ([`reference`]),
//! kept apart from the compiler's code generator so that tests can compare the two, and
//! the value-by-value comparison against a tolerance model ([`compare`]) both use.

pub mod compare;
pub mod reference;
