//! Summed-area tables: the SummedArea pass that builds one (inclusive prefix sums of the
//! unorm codes of a texture, in a storage buffer), and the WGSL box lookup that Shade
//! code reads it with; both follow the one layout (rows of `shadow_size.x` texels,
//! layers one after another).

use crate::back::internal;
use crate::back::text::{f32_lit, header};
use crate::diag::Diagnostic;
use crate::front::ast::{Precision, TableSum};
use crate::ir::{IrPass, PlacedSlot, Program, ResId};
use sshc_graph::{Binding, Draw, FRAME_WGSL, OpCount, Step, Target, View};
use std::fmt::Write as _;

/// How one texture of a summed-area table holds its sums (`TableSum`, by the texture's
/// precision and the pass's `sum`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TableCode {
    /// u32 sums of integer codes `round(s * scale)` of the stored values `s` in [0, 1]:
    /// a unorm texture's own codes (scale 255 or 65535), or a float texture's fixed-point
    /// codes (`Fixed(bits)`: scale 2^bits - 1, `s` the value mapped from the channel's
    /// range onto [0, 1]).
    Codes { scale: u32, fixed: bool },
    /// f32 sums of the stored values less the midpoint of each channel's range.
    Float,
}

impl TableCode {
    /// The WGSL element type of the table's storage buffer.
    pub(crate) fn elem(self) -> &'static str {
        match self {
            TableCode::Codes { .. } => "vec4<u32>",
            TableCode::Float => "vec4<f32>",
        }
    }
}

/// How texture `texture` of summed-area table `table` holds its sums.
pub(crate) fn table_code(ir: &Program, table: ResId, texture: usize) -> Result<TableCode, Diagnostic> {
    let writer = &ir.passes[ir.resources[table].writer].kind;
    if !writer.kind().makes_table() {
        return Err(internal("a summed-area table not written by a SummedArea pass"));
    }
    let sum = writer.table_sum().map(|s| s.0);
    let precision = ir.resources[table]
        .textures
        .get(texture)
        .map(|t| t.precision)
        .ok_or_else(|| internal("a table texture out of range"))?;
    Ok(match (precision, sum) {
        (Precision::Unorm8, _) => TableCode::Codes { scale: 255, fixed: false },
        (Precision::Unorm16, _) => TableCode::Codes {
            scale: 65535,
            fixed: false,
        },
        (Precision::F16 | Precision::F32, None | Some(TableSum::F32)) => TableCode::Float,
        (Precision::F16 | Precision::F32, Some(TableSum::Fixed(bits))) => TableCode::Codes {
            scale: ((1u64 << bits) - 1) as u32,
            fixed: true,
        },
    })
}

/// The stored range `[lo, hi]` of a slot (its range through its encoding); a fixed-point
/// table maps it onto its codes, an f32 table sums values less its midpoint.
pub(crate) fn stored_range(slot: &PlacedSlot) -> (f64, f64) {
    let e = slot.encode;
    let (a, b) = ((slot.range.lo - e.bias) * e.scale, (slot.range.hi - e.bias) * e.scale);
    (a.min(b), a.max(b))
}

/// The midpoint an f32 table subtracts from a slot's stored values: 0 where its range is
/// not finite.
pub(crate) fn centre(slot: &PlacedSlot) -> f64 {
    let (lo, hi) = stored_range(slot);
    let c = 0.5 * (lo + hi);
    if c.is_finite() { c as f32 as f64 } else { 0.0 }
}

/// WGSL decoding one component `x` of a table lookup (the mean of what the table sums,
/// divided by the code scale) to the slot's stored value; the slot's own decode follows.
pub(crate) fn table_decode(code: TableCode, slot: &PlacedSlot, x: &str) -> String {
    match code {
        TableCode::Codes { fixed: false, .. } => x.to_string(),
        TableCode::Codes { fixed: true, .. } => {
            let (lo, hi) = stored_range(slot);
            format!("({} + {x} * {})", f32_lit(lo as f32), f32_lit((hi - lo) as f32))
        }
        TableCode::Float => format!("({x} + {})", f32_lit(centre(slot) as f32)),
    }
}

/// WGSL of a box lookup in summed-area table `t_{name}` (inclusive prefix sums of unorm
/// codes, u32, rows of `shadow_size.x` texels, layers one after another).
///
/// The box [lo, hi] (texel units) covers whole cells i0..i1 less the parts of the first and
/// last cell outside it, on each axis; the weights are separable, so the integral is nine
/// integer rectangles (whole block, two edge columns, two edge rows, four corners), each
/// summed exactly in wrapping u32 arithmetic (exact while a rectangle's sum stays below
/// 2^32: always for unorm8 up to 4096^2 texels, up to 65536 texels of area for unorm16)
/// before it is weighted in f32. A box one texel wide is bilinear interpolation.
///
/// An f32 table ([`TableCode::Float`]) has the same shape in f32: its rectangles are
/// differences of rounded prefix sums, not exact (docs/language.md gives the bound).
pub(crate) fn box_lookup(name: &str, code: TableCode) -> String {
    format!("{}{}", sat_read(name, code), box_mean(name, code))
}

/// WGSL of the table's inclusive prefix sum at a texel (what every table lookup reads).
pub(crate) fn sat_read(name: &str, code: TableCode) -> String {
    let (elem, zero) = match code {
        TableCode::Codes { .. } => ("vec4<u32>", "vec4<u32>(0u)"),
        TableCode::Float => ("vec4<f32>", "vec4<f32>(0.0)"),
    };
    format!(
        "
// inclusive prefix sum at texel (x, y); 0 left of or above the map
fn sat_{name}(x: i32, y: i32, layer: i32) -> {elem} {{
    if x < 0i || y < 0i {{
        return {zero};
    }}
    let n = vec2<i32>(frame.shadow_size.xy);
    return t_{name}[u32((layer * n.y + y) * n.x + x)];
}}
"
    )
}

/// WGSL of `nearest` on a table: the stored value of the texel containing `uv` (clamped to
/// the map), the difference of four prefix sums, exact in u32 before one f32 division (in
/// an f32 table, three rounded f32 subtractions).
pub(crate) fn texel_read(name: &str, code: TableCode) -> String {
    let value = match code {
        TableCode::Codes { scale, .. } => format!("vec4<f32>(s) / {scale}.0"),
        TableCode::Float => "s".to_string(),
    };
    format!(
        "
// the stored value of the texel containing `uv`, clamped to the map
fn texel_{name}(uv: vec2<f32>, layer: i32) -> vec4<f32> {{
    let n = frame.shadow_size.xy;
    let i = clamp(vec2<i32>(floor(uv * n)), vec2<i32>(0i), vec2<i32>(n) - 1i);
    let s = sat_{name}(i.x, i.y, layer) - sat_{name}(i.x - 1i, i.y, layer) - sat_{name}(i.x, i.y - 1i, layer) + sat_{name}(i.x - 1i, i.y - 1i, layer);
    return {value};
}}
"
    )
}

/// WGSL of `sample_box` on a table (after [`sat_read`]).
fn box_mean(name: &str, code: TableCode) -> String {
    // p{y}{x}: the table at x in (i0.x - 1, i0.x, i1.x - 1, i1.x), y likewise: 16 loads
    let mut loads = String::new();
    for y in 0..4 {
        for x in 0..4 {
            let _ = writeln!(loads, "    let p{y}{x} = sat_{name}(xs[{x}], ys[{y}], layer);");
        }
    }
    // a rectangle of whole texels between table columns (xa, xb] and rows (ya, yb]
    let rect = |xa: u32, xb: u32, ya: u32, yb: u32| match code {
        TableCode::Codes { .. } => format!("vec4<f32>(p{yb}{xb} - p{yb}{xa} - p{ya}{xb} + p{ya}{xa})"),
        TableCode::Float => format!("(p{yb}{xb} - p{yb}{xa} - p{ya}{xb} + p{ya}{xa})"),
    };
    let (exact, mean) = match code {
        TableCode::Codes { scale, .. } => ("summed exactly in u32", format!("total / (area * {scale}.0)")),
        TableCode::Float => ("summed in f32", "total / area".to_string()),
    };
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
    // they both removed; each rectangle {exact} before weighting
    let total = {full}
        - a.x * {col0} - b.x * {col1}
        - a.y * {row0} - b.y * {row1}
        + a.x * a.y * {c00} + b.x * a.y * {c10}
        + a.x * b.y * {c01} + b.x * b.y * {c11};
    let area = (hi.x - lo.x) * (hi.y - lo.y);
    return {mean};
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

/// The component-wise constants of layer `layer` of texture `texture` of `res`, as a WGSL
/// `vec4<f32>`: `f` of each slot placed there, 0 (`none`) in a component without one.
fn per_component(res: &crate::ir::PlacedResource, texture: usize, layer: u32, none: f64, f: impl Fn(&PlacedSlot) -> f64) -> String {
    let mut v = [none; 4];
    for slot in res.slots.iter().filter(|s| s.texture == texture && s.layer == layer) {
        if let Some(c) = v.get_mut(slot.component as usize) {
            *c = f(slot);
        }
    }
    let parts: Vec<String> = v.iter().map(|x| f32_lit(*x as f32)).collect();
    format!("vec4<f32>({})", parts.join(", "))
}

/// The row and column steps of a table over a float texture, one loop per layer (each
/// with its channels' constants): fixed-point codes over each channel's stored range, or
/// f32 sums of the values less its midpoint ([`TableCode`]).
fn float_sums(rows: &mut String, cols: &mut String, src: &crate::ir::PlacedResource, ti: usize, dst: &str, code: TableCode) {
    let name = &src.textures[ti].name;
    let zero = match code {
        TableCode::Codes { .. } => "vec4<u32>(0u)",
        TableCode::Float => "vec4<f32>(0.0)",
    };
    for layer in 0..src.textures[ti].layers {
        let load = format!("textureLoad(t_{name}, vec2<u32>(x, y), {layer}u, 0i)");
        let term = match code {
            TableCode::Codes { scale, .. } => {
                let lo = per_component(src, ti, layer, 0.0, |s| stored_range(s).0);
                // a range of one value maps onto code 0
                let width = per_component(src, ti, layer, 1.0, |s| {
                    let (a, b) = stored_range(s);
                    if b > a { b - a } else { 1.0 }
                });
                format!("vec4<u32>(round(clamp(({load} - {lo}) / {width}, vec4<f32>(0.0), vec4<f32>(1.0)) * {scale}.0))")
            }
            TableCode::Float => format!("({load} - {})", per_component(src, ti, layer, 0.0, centre)),
        };
        let _ = write!(
            rows,
            "    {{
        var acc = {zero};
        let row = ({layer}u * n.y + y) * n.x;
        for (var x = 0u; x < n.x; x++) {{
            acc += {term};
            sat_{dst}[row + x] = acc;
        }}
    }}
"
        );
        let _ = write!(
            cols,
            "    {{
        var acc = {zero};
        for (var y = 0u; y < n.y; y++) {{
            let i = ({layer}u * n.y + y) * n.x + x;
            acc += sat_{dst}[i];
            sat_{dst}[i] = acc;
        }}
    }}
"
        );
    }
}

/// A summed-area table in two compute steps: running sums along each row of the unorm
/// codes (`round(v * scale)`, exact integers), then along each column in place. u32
/// addition wraps; box sums taken from the table are exact while they stay below 2^32.
pub(crate) fn summed_area(ir: &Program, pass: &IrPass) -> Result<(String, Vec<Step>), Diagnostic> {
    let src = &ir.resources[pass.reads[0]];
    let dst_id = pass.writes.ok_or_else(|| internal("summed-area pass without output"))?;
    let dst = &ir.resources[dst_id];
    let mut s = header(ir, pass);
    s.push_str(FRAME_WGSL);
    s.push_str("@group(0) @binding(0) var<uniform> frame: Frame;\n");
    for (i, t) in src.textures.iter().enumerate() {
        let _ = writeln!(s, "@group(1) @binding({i}) var t_{}: texture_2d_array<f32>;", t.name);
    }
    let codes: Vec<TableCode> = (0..dst.textures.len())
        .map(|i| table_code(ir, dst_id, i))
        .collect::<Result<_, _>>()?;
    for (i, (t, code)) in dst.textures.iter().zip(&codes).enumerate() {
        let _ = writeln!(
            s,
            "@group(2) @binding({i}) var<storage, read_write> sat_{}: array<{}>;",
            t.name,
            code.elem()
        );
    }
    let mut rows = String::new();
    let mut cols = String::new();
    for (ti, ((st, dt), code)) in src.textures.iter().zip(&dst.textures).zip(&codes).enumerate() {
        let scale = match (st.precision, code) {
            (Precision::Unorm8 | Precision::Unorm16, TableCode::Codes { scale, fixed: false }) => *scale,
            (Precision::F16 | Precision::F32, _) => {
                float_sums(&mut rows, &mut cols, src, ti, &dt.name, *code);
                continue;
            }
            (Precision::Unorm8 | Precision::Unorm16, TableCode::Codes { fixed: true, .. } | TableCode::Float) => {
                return Err(internal("a unorm texture's table not of its codes"));
            }
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
