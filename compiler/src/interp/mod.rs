//! A compiled technique evaluated on the CPU in f64 (`sshc verify`), with the
//! interval about each value that the GPU's f32 arithmetic, its storage rounding, its
//! filtering hardware and its built-in functions may move it by.
//!
//! Given the Depth pass's output (a square map of linear depths per view) and every
//! Geometry pass's ([`Given`]), [`Evaluation::new`] runs every other pass in execution
//! order: Map (the channel expressions per texel, `neighbour` offsets clamped to the edge), Filter (separable Box, Gaussian, Max and Min
//! kernels along x then y, the 3 x 3 Laplacian), Mipmap (levels down to 1 x 1, each texel
//! the mean, maximum or minimum of the 2 x 2 below it) and SummedArea (exact prefix sums).
//! [`Evaluation::visibility`] then evaluates the Shade's visibility for one receiver with
//! the eight lookups as the runtime performs them (texel `(i, j)` centred at uv `((i + 0.5)
//! / N, (j + 0.5) / N)`, clamp to edge, bilinear within a level and linear between levels,
//! `fetch` from `floor(uv N - 0.5)`, `sample_box` integrating the texels the box covers),
//! and clamps it as the runtime stores it (`[0, 1]`, NaN read as 1).
//!
//! Values are exact (f64, the built-in functions folded without rounding by
//! [`crate::builtins::fold_call_exact`]) unless [`Rounding::Stored`] asks for every stored texel to be
//! rounded to its channel's precision and encoding, as the GPU keeps it: the difference of
//! the two evaluations is what storage alone does to the visibility.
//!
//! **The allowance** (the tolerance model of `sshc verify`, a generic form of the agreement
//! tests' model) is a running error bound. Every texel of every stored channel carries one:
//! half its precision's rounding step ([`half_step`]), plus what the pass that wrote it
//! propagates (a filter's weights applied to its inputs' allowances, a maximum's largest, a
//! mip level's mean, a Map channel's bound below). An expression (a Map channel per texel,
//! the Shade's visibility per receiver) is bounded node by node in postorder
//! (`Evaluation::allowed`): a node's error is its own, under the [`Model`],
//!
//! - a lookup: the allowance of the texels it reads, weighted as it weighs them, and the
//!   jump to the neighbour texel where a `nearest` or `fetch` reads within the receiver's
//!   error of a texel boundary;
//! - an input: what the GPU's f32 transforms may leave in it ([`input_error`]: `d` and `uv`
//!   by 2^-20, the others by 2^-20 of their magnitude);
//! - a stored texel: half its rounding step, a whole one for F16 (a device may round F16
//!   stores toward zero, as lavapipe does), and a filtered unorm lookup one code more (a
//!   device may filter in fixed point); a read-back unorm texel an f32 ulp (its conversion);
//! - an arithmetic result: one f32 ulp (three for a division; none for an add, subtract or
//!   multiply of exact operands whose result f32 holds); a built-in: its WGSL accuracy
//!   ([`call_error`]: `sin`, `cos` 2^-11 absolute; `exp`, `exp2` (3 + 2|x|) ulp; `log`,
//!   `log2` 3 ulp or 2^-21 absolute; `pow` as `exp2(y log2 x)`; `sqrt`, `inverseSqrt` 2.5 ulp;
//!   the inverse trigonometric functions 4096 ulp) plus an ulp where it rounds,
//!
//! plus, for each operand and each of its components, the largest change of the node when
//! that component alone moves by its error either way (a bool operand flips). A clamp thus
//! passes on only what crosses it; a comparison or a `select` whose operands may cross passes
//! on the whole jump, so binary tests at exact ties need no separate rule; an operand that
//! may be anything (an unbounded error) makes the node unbounded. The Shade's interval is its
//! raw value (NaN read as 1) widened by the root's bound and then clamped to `[0, 1]`, widened
//! once more by what moving every filtered lookup together by the hardware's 8-bit texel
//! positions and level fractions (`FILTER_SHIFT`) changes: the GPU weighs every channel
//! of a texel with the same weights, so that error is coherent across the lookups of one
//! receiver, not independent per lookup.
//!
//! The bound is linear in each operand and sums over operands: it is not a proof where
//! errors interact beyond first order, and it is loose where an expression amplifies every
//! error (MSM's Cholesky on flat moments; `sshc verify` counts such receivers as loose).
//!
//! **Given texels.** What the GPU rasterises is not recomputed: the Depth pass's output
//! and every Geometry pass's (cones, sheets, ribbons, back faces and skins are drawn from
//! the scene's meshes) are [`Given`], one map per view, and the evaluation starts after them.
//! A depth map given from a synthetic field checks every pass after Depth; one read back
//! from the GPU (`given_slots` names the textures) checks the passes after it and the
//! Shade, not the rasterisation itself. Per-sample views (`Depth(view: PerSample)`, Skins)
//! take one map per light sample, and the Shade's `at_sample(k, ..)` reads the receiver as
//! light sample k sees it ([`Seen`]).
//!
//! One job per file: `inputs.rs` (the frame, the receiver and the values of built-in
//! inputs), `given.rs` (the texels given rather than computed), `model.rs` (the precision
//! and rounding model: storage, f32 arithmetic, the allowed interval), `texels.rs` (stored
//! levels and their lookups), `table.rs` (summed-area tables as the GPU builds them),
//! `evaluation.rs` (the public entry points: `Evaluation`, `Scratch`), `passes.rs` (each
//! pass kind run in execution order) and `expr.rs` (an expression's value and its running
//! error bound).

mod evaluation;
mod expr;
mod given;
mod inputs;
mod model;
mod passes;
mod table;
#[cfg(test)]
mod tests;
mod texels;

pub use evaluation::{Evaluation, Scratch};
pub use given::{Given, GivenSlot, given_slots};
pub use inputs::{Frame, Receiver, Seen, noise};
pub use model::{Allowed, Model, Rounding, call_error, half_step, input_error, stored};
