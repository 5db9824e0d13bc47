//! WGSL both sides emit: the receiver's normal, the shaded colour, the receiver-plane depth
//! slope and the octahedral normal encoding, shared by the compiler's Shade and the
//! runtime's own steps.

/// The receiver's normal in WGSL, in a fragment entry whose input `in` has `world` and
/// `normal`: surfaces are two-sided, and the receiver is the side the camera sees. Defines
/// `n`. The compiler's Shade passes and the runtime's draw of objects that receive no
/// shadow share it.
pub const SHADE_NORMAL_WGSL: &str = "    // Two-sided surfaces: the receiver is the side the camera sees. The triangle's own
    // normal from screen-space derivatives, cross(dpdy, dpdx) of the world position, faces
    // the camera whatever the winding (framebuffer y runs down); the interpolated normal is
    // turned to its side, so a smooth normal at a silhouette keeps its sign.
    let in_face = cross(dpdy(in.world), dpdx(in.world));
    let in_smooth = normalize(in.normal);
    let n = select(in_smooth, -in_smooth, dot(in_smooth, in_face) < 0.0);
";

/// The shaded colour of the camera image in WGSL, an expression of the visibility `vis`
/// and `lambert` (`max(n . l, 0)`): 12 % ambient, the rest lit. The compiler's Shade passes
/// and the runtime's draw of objects that receive no shadow (`vis` = 1) share it.
pub const SHADE_COLOR_WGSL: &str = "vec4<f32>(vec3<f32>(0.12 + 0.88 * vis * lambert), 1.0)";

/// The receiver-plane depth slope (Isidoro 2006) in WGSL: from the derivatives over the
/// screen of the light-space uv (`duv_dx`, `duv_dy`) and of the normalised depth (`dd_dx`,
/// `dd_dy`), solve `[duv/dx; duv/dy] g = [dd/dx; dd/dy]` and define `in_depth_slope`
/// (`|g|` in texels, at most 0.1; 0 where the Jacobian is singular). The compiler's Shade
/// passes take the derivatives from the hardware (`dpdx`, `dpdy`); the runtime's step that
/// turns a host's pixels into the G-buffer from neighbouring pixels. One definition for both.
pub const DEPTH_SLOPE_WGSL: &str = "    let det = duv_dx.x * duv_dy.y - duv_dx.y * duv_dy.x;
    let g = vec2<f32>(dd_dx * duv_dy.y - duv_dx.y * dd_dy, duv_dx.x * dd_dy - dd_dx * duv_dy.x);
    let in_depth_slope = select(0.0, min(length(g / det) * frame.shadow_size.z, 0.1), abs(det) > 1e-14);
";

/// The G-buffer's normal encoding in WGSL: `octahedral` and its inverse `from_octahedral`
/// (Cigolle et al. 2014, section 3.1), shared by the compiler's deferred Shade and the
/// runtime's host pixels.
pub const OCTAHEDRAL_WGSL: &str = "// Octahedral encoding of a unit vector (Cigolle et al. 2014, section 3.1).
fn octahedral(v: vec3<f32>) -> vec2<f32> {
    let p = v.xy / (abs(v.x) + abs(v.y) + abs(v.z));
    let sign = select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    return select((1.0 - abs(p.yx)) * sign, p, v.z >= 0.0);
}

fn from_octahedral(e: vec2<f32>) -> vec3<f32> {
    var v = vec3<f32>(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-v.z, 0.0);
    let sign = select(vec2<f32>(1.0), vec2<f32>(-1.0), v.xy >= vec2<f32>(0.0));
    v = vec3<f32>(v.xy + t * sign, v.z);
    return normalize(v);
}
";
