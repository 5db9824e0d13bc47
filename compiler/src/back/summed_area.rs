//! Summed-area tables: the SummedArea pass that builds one (inclusive prefix sums of the
//! unorm codes of a texture, in a storage buffer), and the WGSL box lookup that Shade
//! code reads it with; both follow the one layout (rows of `shadow_size.x` texels,
//! layers one after another).

use crate::back::internal;
use crate::back::text::header;
use crate::diag::Diagnostic;
use crate::front::ast::Precision;
use crate::ir::{IrPass, Program};
use sshc_graph::{Binding, Draw, FRAME_WGSL, OpCount, Step, Target, View};
use std::fmt::Write as _;

/// WGSL of a box lookup in summed-area table `t_{name}` (inclusive prefix sums of unorm
/// codes, u32, rows of `shadow_size.x` texels, layers one after another).
///
/// The box [lo, hi] (texel units) covers whole cells i0..i1 less the parts of the first and
/// last cell outside it, on each axis; the weights are separable, so the integral is nine
/// integer rectangles (whole block, two edge columns, two edge rows, four corners), each
/// summed exactly in wrapping u32 arithmetic (exact while a rectangle's sum stays below
/// 2^32: always for unorm8 up to 4096^2 texels, up to 65536 texels of area for unorm16)
/// before it is weighted in f32. A box one texel wide is bilinear interpolation.
pub(crate) fn box_lookup(name: &str, scale: u32) -> String {
    format!("{}{}", sat_read(name), box_mean(name, scale))
}

/// WGSL of the table's inclusive prefix sum at a texel (what every table lookup reads).
pub(crate) fn sat_read(name: &str) -> String {
    format!(
        "
// inclusive prefix sum at texel (x, y); 0 left of or above the map
fn sat_{name}(x: i32, y: i32, layer: i32) -> vec4<u32> {{
    if x < 0i || y < 0i {{
        return vec4<u32>(0u);
    }}
    let n = vec2<i32>(frame.shadow_size.xy);
    return t_{name}[u32((layer * n.y + y) * n.x + x)];
}}
"
    )
}

/// WGSL of `nearest` on a table: the stored value of the texel containing `uv` (clamped to
/// the map), the difference of four prefix sums, exact in u32 before one f32 division.
pub(crate) fn texel_read(name: &str, scale: u32) -> String {
    format!(
        "
// the stored value of the texel containing `uv`, clamped to the map
fn texel_{name}(uv: vec2<f32>, layer: i32) -> vec4<f32> {{
    let n = frame.shadow_size.xy;
    let i = clamp(vec2<i32>(floor(uv * n)), vec2<i32>(0i), vec2<i32>(n) - 1i);
    let s = sat_{name}(i.x, i.y, layer) - sat_{name}(i.x - 1i, i.y, layer) - sat_{name}(i.x, i.y - 1i, layer) + sat_{name}(i.x - 1i, i.y - 1i, layer);
    return vec4<f32>(s) / {scale}.0;
}}
"
    )
}

/// WGSL of `sample_box` on a table (after [`sat_read`]).
fn box_mean(name: &str, scale: u32) -> String {
    // p{y}{x}: the table at x in (i0.x - 1, i0.x, i1.x - 1, i1.x), y likewise: 16 loads
    let mut loads = String::new();
    for y in 0..4 {
        for x in 0..4 {
            let _ = writeln!(loads, "    let p{y}{x} = sat_{name}(xs[{x}], ys[{y}], layer);");
        }
    }
    // a rectangle of whole texels between table columns (xa, xb] and rows (ya, yb]
    let rect = |xa: u32, xb: u32, ya: u32, yb: u32| format!("vec4<f32>(p{yb}{xb} - p{yb}{xa} - p{ya}{xb} + p{ya}{xa})");
    format!(
        "
// mean stored value over a box `w` (uv units, at least one texel) centred at `uv`, clipped to the map
fn box_{name}(uv: vec2<f32>, w: vec2<f32>, layer: i32) -> vec4<f32> {{
    let n = frame.shadow_size.xy;
    let half = max(w * n, vec2<f32>(1.0)) * 0.5;
    let c = clamp(uv * n, vec2<f32>(0.0), n);
    let lo = clamp(c - half, vec2<f32>(0.0), n);
    let hi = clamp(c + half, vec2<f32>(0.0), n);
    let last = vec2<i32>(n) - 1i;
    let i0 = min(vec2<i32>(floor(lo)), last);
    let i1 = min(vec2<i32>(floor(hi)), last);
    // parts of the first and last cells outside the box
    let a = lo - vec2<f32>(i0);
    let b = vec2<f32>(i1) + 1.0 - hi;
    let xs = vec4<i32>(i0.x - 1i, i0.x, i1.x - 1i, i1.x);
    let ys = vec4<i32>(i0.y - 1i, i0.y, i1.y - 1i, i1.y);
{loads}    // whole block, less the outside parts of the edge columns and rows, plus the corners
    // they both removed; each rectangle summed exactly in u32 before weighting
    let total = {full}
        - a.x * {col0} - b.x * {col1}
        - a.y * {row0} - b.y * {row1}
        + a.x * a.y * {c00} + b.x * a.y * {c10}
        + a.x * b.y * {c01} + b.x * b.y * {c11};
    let area = (hi.x - lo.x) * (hi.y - lo.y);
    return total / (area * {scale}.0);
}}
",
        full = rect(0, 3, 0, 3),
        col0 = rect(0, 1, 0, 3),
        col1 = rect(2, 3, 0, 3),
        row0 = rect(0, 3, 0, 1),
        row1 = rect(0, 3, 2, 3),
        c00 = rect(0, 1, 0, 1),
        c10 = rect(2, 3, 0, 1),
        c01 = rect(0, 1, 2, 3),
        c11 = rect(2, 3, 2, 3),
    )
}

/// A summed-area table in two compute steps: running sums along each row of the unorm
/// codes (`round(v * scale)`, exact integers), then along each column in place. u32
/// addition wraps; box sums taken from the table are exact while they stay below 2^32.
pub(crate) fn summed_area(ir: &Program, pass: &IrPass) -> Result<(String, Vec<Step>), Diagnostic> {
    let src = &ir.resources[pass.reads[0]];
    let dst = &ir.resources[pass.writes.ok_or_else(|| internal("summed-area pass without output"))?];
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n");
    for (i, t) in src.textures.iter().enumerate() {
        let _ = writeln!(s, "@group(1) @binding({i}) var t_{}: texture_2d_array<f32>;", t.name);
    }
    for (i, t) in dst.textures.iter().enumerate() {
        let _ = writeln!(
            s,
            "@group(2) @binding({i}) var<storage, read_write> sat_{}: array<vec4<u32>>;",
            t.name
        );
    }
    let mut rows = String::new();
    let mut cols = String::new();
    for (st, dt) in src.textures.iter().zip(&dst.textures) {
        let scale = match st.precision {
            Precision::Unorm8 => 255,
            Precision::Unorm16 => 65535,
            Precision::F16 | Precision::F32 => return Err(internal("summed-area table over a non-unorm texture")),
        };
        let _ = write!(
            rows,
            "    for (var layer = 0u; layer < {layers}u; layer++) {{
        var acc = vec4<u32>(0u);
        let row = (layer * n.y + y) * n.x;
        for (var x = 0u; x < n.x; x++) {{
            acc += vec4<u32>(round(textureLoad(t_{src}, vec2<u32>(x, y), layer, 0i) * {scale}.0));
            sat_{dst}[row + x] = acc;
        }}
    }}
",
            layers = st.layers,
            src = st.name,
            dst = dt.name
        );
        let _ = write!(
            cols,
            "    for (var layer = 0u; layer < {layers}u; layer++) {{
        var acc = vec4<u32>(0u);
        for (var y = 0u; y < n.y; y++) {{
            let i = (layer * n.y + y) * n.x + x;
            acc += sat_{dst}[i];
            sat_{dst}[i] = acc;
        }}
    }}
",
            layers = dt.layers,
            dst = dt.name
        );
    }
    let wg = sshc_graph::COMPUTE_WORKGROUP;
    let _ = write!(
        s,
        "
// one invocation per row: running sums of the unorm codes along the row
@compute @workgroup_size({wg})
fn cs_rows(@builtin(global_invocation_id) id: vec3<u32>) {{
    let n = vec2<u32>(frame.shadow_size.xy);
    let y = id.x;
    if y >= n.y {{
        return;
    }}
{rows}}}

// one invocation per column: running sums down the column, in place
@compute @workgroup_size({wg})
fn cs_columns(@builtin(global_invocation_id) id: vec3<u32>) {{
    let n = vec2<u32>(frame.shadow_size.xy);
    let x = id.x;
    if x >= n.x {{
        return;
    }}
{cols}}}
"
    );
    let writes: Vec<Target> = dst
        .textures
        .iter()
        .map(|t| Target {
            texture: t.name.clone(),
            layer: 0,
        })
        .collect();
    let compute_step = |entry: &str, draw: Draw, reads: Vec<Binding>| Step {
        vertex: None,
        fragment: None,
        compute: Some(entry.to_string()),
        draw,
        reads,
        writes: writes.clone(),
        params: false,
        sampler: false,
        light_samples: false,
        cost: OpCount::default(),
    };
    let reads = src
        .textures
        .iter()
        .enumerate()
        .map(|(i, t)| Binding {
            binding: i as u32,
            texture: t.name.clone(),
            view: View::Base,
        })
        .collect();
    Ok((
        s,
        vec![
            compute_step("cs_rows", Draw::ComputeRows, reads),
            compute_step("cs_columns", Draw::ComputeColumns, vec![]),
        ],
    ))
}
