//! Implementation of the `sshc_shaders_gen::technique!` proc macro.
//!
//! The proc-macro crate `sshc-shaders-gen` is a thin shell over this library (the split of
//! `encase_derive` / `encase_derive_impl`): the work happens here on `proc_macro2` tokens, so
//! it can be unit-tested and reused, and it depends on the compiler library `sshc` without
//! its `gpu` feature, so no wgpu is built for the macro.
//!
//! ```text
//! technique!(
//!     #[doc = "..."]                                 // optional outer attributes
//!     pub mod pcf = "../techniques/pcf.ron",         // path relative to CARGO_MANIFEST_DIR
//!     set: { N = 5, bias = 0.001 },                  // optional: `sshc --set NAME=VALUE`
//!     precision: { z = F16 },                        // optional: `sshc --precision NAME=P`
//!     graph: ::sshc_graph,                           // optional: path of the graph-schema crate
//! );
//! ```
//!
//! The expansion is a module holding the WGSL of every pass, the pass graph as RON and a
//! function parsing it into `sshc_graph::PassGraph`, the values of the fixed params,
//! and a `#[repr(C)]` `Params` struct whose layout is checked against the WGSL `Params`
//! uniform (as laid out by naga's `Layouter`) by compile-time assertions. See [`expand`].

use proc_macro2::{Span, TokenStream};
use quote::ToTokens;
use quote::{format_ident, quote, quote_spanned};
use sshc_graph::{ParamDecl, ParamType, PassGraph};
use std::path::{Path, PathBuf};
use syn::ext::IdentExt;
use syn::parse::{Parse, ParseStream};
use syn::{Attribute, Ident, LitStr, Token, Visibility, braced};

/// Environment variable that, when set, replaces `CARGO_MANIFEST_DIR` as the directory
/// technique paths are resolved against. Tests that compile crates out of their source tree
/// (trybuild) set it; ordinary builds leave it unset.
pub const BASE_DIR_ENV: &str = "SSHC_SHADERS_GEN_BASE_DIR";

/// The parsed macro input.
pub struct TechniqueInput {
    pub attrs: Vec<Attribute>,
    pub vis: Visibility,
    pub name: Ident,
    /// The technique file, relative to the using crate's manifest directory.
    pub path: LitStr,
    /// `set: { NAME = VALUE, .. }`: (name, RON literal text).
    pub set: Vec<(String, String)>,
    /// `precision: { NAME = P, .. }`.
    pub precision: Vec<(String, String)>,
    /// `graph: path`: where the generated code finds the `sshc_graph` crate.
    pub graph: Option<syn::Path>,
}

const USAGE: &str = "expected `technique!(pub mod NAME = \"path/to/technique.ron\")`, optionally followed by \
                     `, set: { NAME = VALUE, .. }`, `, precision: { NAME = PRECISION, .. }` and `, graph: path::to::sshc_graph`";

impl Parse for TechniqueInput {
    fn parse(input: ParseStream) -> syn::Result<Self> {
        let attrs = input.call(Attribute::parse_outer)?;
        let vis: Visibility = input.parse()?;
        if !input.peek(Token![mod]) {
            return Err(input.error(USAGE));
        }
        input.parse::<Token![mod]>()?;
        let name: Ident = input
            .parse()
            .map_err(|e| syn::Error::new(e.span(), format!("expected the module's name; {USAGE}")))?;
        if !input.peek(Token![=]) {
            return Err(input.error(USAGE));
        }
        input.parse::<Token![=]>()?;
        let path: LitStr = input
            .parse()
            .map_err(|e| syn::Error::new(e.span(), format!("expected the technique file as a string literal; {USAGE}")))?;
        let mut out = TechniqueInput {
            attrs,
            vis,
            name,
            path,
            set: Vec::new(),
            precision: Vec::new(),
            graph: None,
        };
        let mut seen: Vec<String> = Vec::new();
        while !input.is_empty() {
            input.parse::<Token![,]>()?;
            if input.is_empty() {
                break;
            }
            let key: Ident = input.parse()?;
            let k = key.to_string();
            if seen.contains(&k) {
                return Err(syn::Error::new(key.span(), format!("`{k}` is given twice")));
            }
            input.parse::<Token![:]>()?;
            match k.as_str() {
                "set" => out.set = parse_pairs(input, parse_set_value)?,
                "precision" => out.precision = parse_pairs(input, parse_precision_value)?,
                "graph" => out.graph = Some(input.parse()?),
                _ => {
                    return Err(syn::Error::new(
                        key.span(),
                        format!("unknown option `{k}`: expected `set`, `precision` or `graph`"),
                    ));
                }
            }
            seen.push(k);
        }
        Ok(out)
    }
}

/// `{ KEY = VALUE, .. }` where KEY is an identifier or a string literal.
fn parse_pairs(input: ParseStream, value: fn(ParseStream) -> syn::Result<String>) -> syn::Result<Vec<(String, String)>> {
    let content;
    braced!(content in input);
    let mut pairs = Vec::new();
    while !content.is_empty() {
        let key = if content.peek(LitStr) {
            content.parse::<LitStr>()?.value()
        } else {
            content.call(Ident::parse_any)?.to_string()
        };
        content.parse::<Token![=]>()?;
        pairs.push((key, value(&content)?));
        if content.is_empty() {
            break;
        }
        content.parse::<Token![,]>()?;
    }
    Ok(pairs)
}

/// A param value as the RON literal `--set` expects: a number (optionally negative), a
/// boolean, or a string literal holding the RON text.
fn parse_set_value(input: ParseStream) -> syn::Result<String> {
    let neg = if input.peek(Token![-]) {
        input.parse::<Token![-]>()?;
        "-"
    } else {
        ""
    };
    let lit: syn::Lit = input.parse()?;
    let text = match &lit {
        syn::Lit::Int(i) => i.base10_digits().to_string(),
        syn::Lit::Float(f) => f.base10_digits().to_string(),
        syn::Lit::Bool(b) if neg.is_empty() => b.value.to_string(),
        syn::Lit::Str(s) if neg.is_empty() => s.value(),
        _ => return Err(syn::Error::new(lit.span(), "expected a number, `true`, `false` or a string")),
    };
    Ok(format!("{neg}{text}"))
}

/// A precision: an identifier (`F16`) or a string (`"F16"`).
fn parse_precision_value(input: ParseStream) -> syn::Result<String> {
    if input.peek(LitStr) {
        Ok(input.parse::<LitStr>()?.value())
    } else {
        Ok(input.call(Ident::parse_any)?.to_string())
    }
}

/// The macro: parse, resolve the file against `CARGO_MANIFEST_DIR` (or [`BASE_DIR_ENV`]),
/// compile, generate. Every error becomes a `compile_error!` in the returned tokens.
pub fn expand(input: TokenStream) -> TokenStream {
    let parsed: TechniqueInput = match syn::parse2(input) {
        Ok(p) => p,
        Err(e) => return e.to_compile_error(),
    };
    let base = std::env::var_os(BASE_DIR_ENV).or_else(|| std::env::var_os("CARGO_MANIFEST_DIR"));
    let Some(base) = base else {
        return error(
            parsed.path.span(),
            "CARGO_MANIFEST_DIR is not set: build with cargo, which sets it, so that the technique path can be resolved",
        );
    };
    expand_in(&parsed, Path::new(&base))
}

/// [`expand`] with an explicit base directory for the technique path.
pub fn expand_in(input: &TechniqueInput, base: &Path) -> TokenStream {
    match generate(input, base) {
        Ok(t) => t,
        Err(e) => e,
    }
}

fn error(span: Span, message: &str) -> TokenStream {
    quote_spanned!(span=> ::core::compile_error!(#message);)
}

/// Where the technique file lies and its text.
fn read_technique(input: &TechniqueInput, base: &Path) -> Result<(PathBuf, String), TokenStream> {
    let rel = input.path.value();
    let full = base.join(&rel);
    let span = input.path.span();
    match std::fs::read_to_string(&full) {
        // Canonical where possible, so the embedded path and the build's dep-info read plainly.
        Ok(text) => Ok((full.canonicalize().unwrap_or(full), text)),
        Err(e) => {
            let what = match e.kind() {
                std::io::ErrorKind::NotFound => "no such file".to_string(),
                _ => e.to_string(),
            };
            Err(error(
                span,
                &format!("cannot read technique file `{rel}`: {what} (paths are relative to the directory of the crate's Cargo.toml)"),
            ))
        }
    }
}

/// The layout naga computes for the WGSL `Params` struct: (member name, offset, size, kind)
/// and the struct's size rounded up as a uniform buffer binding requires.
#[derive(Debug, PartialEq)]
pub struct UniformLayout {
    pub members: Vec<(String, u32, u32, naga::ScalarKind)>,
    /// naga's span of the struct.
    pub span: u32,
    /// `span` rounded up to the 16 bytes of a uniform.
    pub uniform_size: u32,
}

/// Lay out the `Params` struct of one WGSL module with `naga::proc::Layouter`; `Ok(None)`
/// when the module declares no `Params`.
pub fn params_layout(wgsl: &str) -> Result<Option<UniformLayout>, String> {
    let module = naga::front::wgsl::parse_str(wgsl).map_err(|e| e.emit_to_string(wgsl))?;
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).map_err(|e| e.to_string())?;
    for (handle, ty) in module.types.iter() {
        if ty.name.as_deref() != Some("Params") {
            continue;
        }
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            return Err("`Params` is not a struct".into());
        };
        let mut out = Vec::new();
        let mut end = 0u32;
        for m in members {
            let layout = layouter[m.ty];
            // Recompute the offset from the layouter's alignments and check the frontend's.
            let offset = layout.alignment.round_up(end);
            if offset != m.offset {
                return Err(format!(
                    "member `{}`: naga's layouter places it at {offset}, the module at {}",
                    m.name.as_deref().unwrap_or("?"),
                    m.offset
                ));
            }
            end = offset + layout.size;
            let kind = match module.types[m.ty].inner {
                naga::TypeInner::Scalar(s) if s.width == 4 => s.kind,
                ref other => {
                    return Err(format!(
                        "member `{}` is {other:?}, not a 4-byte scalar",
                        m.name.as_deref().unwrap_or("?")
                    ));
                }
            };
            out.push((m.name.clone().unwrap_or_default(), offset, layout.size, kind));
        }
        let struct_layout = layouter[handle];
        if struct_layout.size != *span {
            return Err(format!(
                "the layouter sizes `Params` at {}, the module at {span}",
                struct_layout.size
            ));
        }
        return Ok(Some(UniformLayout {
            members: out,
            span: *span,
            uniform_size: naga::proc::Alignment::MIN_UNIFORM.round_up(*span),
        }));
    }
    Ok(None)
}

/// Rust's keywords in every edition, reserved ones included: these names become raw
/// identifiers (`r#dyn`) whatever edition the using crate is in.
const RUST_KEYWORDS: &[&str] = &[
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for", "if", "impl", "in", "let", "loop",
    "match", "mod", "move", "mut", "pub", "ref", "return", "self", "Self", "static", "struct", "super", "trait", "true", "type", "unsafe",
    "use", "where", "while", "async", "await", "dyn", "abstract", "become", "box", "do", "final", "macro", "override", "priv", "typeof",
    "unsized", "virtual", "yield", "try", "gen",
];

/// A Rust identifier for a technique name: itself, raw (`r#dyn`) for a keyword, or with a
/// trailing `_` where even a raw identifier is refused (`self`, `crate`, ...).
fn rust_ident(name: &str) -> Ident {
    match name {
        "self" | "Self" | "super" | "crate" | "_" => format_ident!("{}_", name),
        _ if RUST_KEYWORDS.contains(&name) => Ident::new_raw(name, Span::call_site()),
        _ if syn::parse_str::<Ident>(name).is_ok() => Ident::new(name, Span::call_site()),
        _ => format_ident!(
            "p_{}",
            name.chars()
                .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
                .collect::<String>()
        ),
    }
}

/// `NAME_WGSL` constant names for the passes, made unique.
fn shader_const_names(files: &[(String, String)], graph: &PassGraph) -> Vec<Ident> {
    let mut used: Vec<String> = Vec::new();
    files
        .iter()
        .enumerate()
        .map(|(i, (file, _))| {
            let pass = graph.passes.iter().find(|p| &p.shader == file).map(|p| p.name.clone());
            let stem = pass.unwrap_or_else(|| format!("module{i}"));
            let mut name: String = stem
                .chars()
                .map(|c| if c.is_ascii_alphanumeric() { c.to_ascii_uppercase() } else { '_' })
                .collect();
            if name.is_empty() || name.starts_with(|c: char| c.is_ascii_digit()) {
                name.insert(0, 'P');
            }
            name.push_str("_WGSL");
            while used.contains(&name) || name == "GRAPH_RON" {
                name = format!("{}_{i}", name);
            }
            used.push(name.clone());
            format_ident!("{}", name)
        })
        .collect()
}

fn generate(input: &TechniqueInput, base: &Path) -> Result<TokenStream, TokenStream> {
    let (full, source) = read_technique(input, base)?;
    let rel = input.path.value();
    let span = input.path.span();
    let opts = sshc::CompileOptions {
        set: input.set.clone(),
        precision: input.precision.clone(),
        ..Default::default()
    };
    let compiled = match sshc::compile_str(&source, &opts) {
        Ok(c) => c,
        Err(d) if d.is_empty() => return Err(error(span, &format!("technique `{rel}` did not compile (no diagnostic)"))),
        Err(d) => {
            let text = d.render(&rel, &source);
            return Err(error(span, &format!("technique `{rel}` does not compile:\n{}", text.trim_end())));
        }
    };
    let internal = |m: String| error(span, &format!("sshc-shaders-gen: internal error on `{rel}`: {m}"));
    let full_str = full
        .to_str()
        .ok_or_else(|| error(span, &format!("the path of `{rel}` is not valid UTF-8, which include_str! needs")))?
        .to_string();
    let graph = &compiled.graph;

    // The WGSL `Params` layout: the declaration the code generator writes, laid out by naga
    // on its own (a technique whose runtime params no shader reads still gets its uniform),
    // and the same in every module that declares it.
    let uniform: Vec<&ParamDecl> = graph.params.iter().filter(|p| p.offset.is_some()).collect();
    let mut layout: Option<UniformLayout> = None;
    if !uniform.is_empty() {
        let decl = format!("{}@group(0) @binding(1) var<uniform> params: Params;\n", compiled.params_struct());
        let l = params_layout(&decl).map_err(|e| internal(format!("the `Params` declaration: {e}")))?;
        layout = Some(l.ok_or_else(|| internal("the `Params` declaration declares no `Params`".into()))?);
    }
    // Messages name the last module that declares it (the Shade pass, where there is one).
    let mut layout_file = None;
    for (file, src) in compiled.shaders.iter().rev() {
        let l = params_layout(src).map_err(|e| internal(format!("{file}: {e}")))?;
        if let Some(l) = l {
            if layout.as_ref() != Some(&l) {
                return Err(internal(format!("`Params` in {file} is not laid out as the graph's params")));
            }
            layout_file.get_or_insert_with(|| file.clone());
        }
    }
    let layout_file = layout_file.unwrap_or_else(|| "the generated `Params` declaration".to_string());
    let (members, uniform_size) = match layout {
        Some(l) => (l.members, l.uniform_size),
        None => (Vec::new(), 0),
    };
    if members.len() != uniform.len() || uniform_size != graph.params_size {
        return Err(internal(format!(
            "the graph declares {} uniform params in {} bytes, the WGSL `Params` {} members in {} bytes",
            uniform.len(),
            graph.params_size,
            members.len(),
            uniform_size
        )));
    }

    let graph_crate = match &input.graph {
        Some(p) => quote!(#p),
        None => quote!(::sshc_graph),
    };

    // Params fields, with types as the technique declares them, checked against naga's.
    let mut field_idents: Vec<Ident> = Vec::new();
    let mut fields = Vec::new();
    let mut defaults = Vec::new();
    let mut asserts = Vec::new();
    let mut writes = Vec::new();
    let mut values = Vec::new();
    let mut names = Vec::new();
    for (p, (mname, offset, size, kind)) in uniform.iter().zip(&members) {
        if &p.name != mname || p.offset != Some(*offset) {
            return Err(internal(format!(
                "param `{}` at byte {:?} of the graph is member `{mname}` at byte {offset} in the WGSL",
                p.name, p.offset
            )));
        }
        let (ty, expected_kind, default) = match p.ty {
            ParamType::F32 => {
                let v = p.value as f32;
                if !v.is_finite() {
                    return Err(internal(format!("param `{}` has no finite f32 default", p.name)));
                }
                (
                    quote!(f32),
                    naga::ScalarKind::Float,
                    proc_macro2::Literal::f32_suffixed(v).into_token_stream(),
                )
            }
            ParamType::I32 => (
                quote!(i32),
                naga::ScalarKind::Sint,
                proc_macro2::Literal::i32_suffixed(p.value as i32).into_token_stream(),
            ),
            ParamType::Bool => (
                quote!(u32),
                naga::ScalarKind::Uint,
                proc_macro2::Literal::u32_suffixed(u32::from(p.value != 0.0)).into_token_stream(),
            ),
        };
        if *kind != expected_kind {
            return Err(internal(format!(
                "param `{}` is {:?} in the graph, {kind:?} in the WGSL",
                p.name, p.ty
            )));
        }
        let id = rust_ident(&p.name);
        let doc = param_doc(p);
        fields.push(quote! { #[doc = #doc] pub #id: #ty, });
        defaults.push(quote! { #id: #default, });
        let off = *offset as usize;
        let size = *size as usize;
        let name = &p.name;
        let msg_off = format!("Params.{name}: its offset differs from the WGSL `Params` uniform ({layout_file}, naga layouter)");
        let msg_size = format!("Params.{name}: its size differs from the WGSL `Params` uniform");
        asserts.push(quote! {
            ::core::assert!(::core::mem::offset_of!(Params, #id) == #off, #msg_off);
            ::core::assert!(::core::mem::size_of::<#ty>() == #size, #msg_size);
        });
        writes.push(quote! {
            let o = ::core::mem::offset_of!(Params, #id);
            b[o..o + 4].copy_from_slice(&self.#id.to_le_bytes());
        });
        values.push(quote! { (#name, self.#id as f64), });
        names.push(name.clone());
        field_idents.push(id);
    }
    // Padding up to the uniform's size, so that `size_of::<Params>()` is the binding size.
    let end = members.last().map(|m| m.1 + m.2).unwrap_or(0);
    let pad_words = ((uniform_size - end.min(uniform_size)) / 4) as usize;
    let pad_field = if pad_words > 0 {
        let mut pad = "_pad".to_string();
        while field_idents.iter().any(|f| *f == pad) {
            pad.push('_');
        }
        let pad = format_ident!("{}", pad);
        defaults.push(quote! { #pad: [0; #pad_words], });
        quote! {
            /// Padding up to the 16-byte multiple a uniform binding takes; never read.
            pub #pad: [u32; #pad_words],
        }
    } else {
        quote!()
    };
    let size = uniform_size as usize;
    let size_msg = format!("Params: its size differs from the WGSL `Params` uniform rounded to 16 bytes ({layout_file})");
    let graph_msg = "Params: its size differs from the graph's `params_size`";
    let n_uniform = names.len();

    // Fixed params: compiled-in constants.
    let fixed: Vec<TokenStream> = graph
        .params
        .iter()
        .filter(|p| p.offset.is_none())
        .map(|p| {
            let id = rust_ident(&p.name);
            let doc = param_doc(p);
            let (ty, v) = match p.ty {
                ParamType::F32 => (quote!(f32), {
                    let v = p.value as f32;
                    if v.is_finite() {
                        proc_macro2::Literal::f32_suffixed(v).into_token_stream()
                    } else {
                        quote!(f32::NAN)
                    }
                }),
                ParamType::I32 => (quote!(i32), proc_macro2::Literal::i32_suffixed(p.value as i32).into_token_stream()),
                ParamType::Bool => (quote!(bool), if p.value != 0.0 { quote!(true) } else { quote!(false) }),
            };
            quote! { #[doc = #doc] pub const #id: #ty = #v; }
        })
        .collect();

    let consts = shader_const_names(&compiled.shaders, graph);
    let sources: Vec<&String> = compiled.shaders.iter().map(|(_, s)| s).collect();
    let files: Vec<&String> = compiled.shaders.iter().map(|(f, _)| f).collect();
    let shader_docs: Vec<String> = files.iter().map(|f| format!("WGSL of `{f}`.")).collect();
    let graph_ron = graph.to_ron();
    let warnings: Vec<String> = compiled.warnings.iter().map(|w| w.render(&rel, &source)).collect();
    let technique = &graph.technique;
    let params_size = graph.params_size;

    let attrs = &input.attrs;
    let vis = &input.vis;
    let name = &input.name;
    let mod_doc = format!("Technique `{technique}`, compiled at build time from `{rel}` by `sshc_shaders_gen::technique!`.");
    Ok(quote! {
        #(#attrs)*
        #[doc = #mod_doc]
        #[allow(dead_code, non_snake_case, non_upper_case_globals, clippy::all)]
        #vis mod #name {
            /// The technique's name.
            pub const TECHNIQUE: &str = #technique;
            /// The technique file, as resolved when the crate was built.
            pub const SOURCE_PATH: &str = #full_str;
            /// The technique's source text (including it makes the build depend on the file).
            pub const SOURCE: &str = ::core::include_str!(#full_str);
            /// The pass graph, as `sshc compile` writes `<technique>.graph.ron`.
            pub const GRAPH_RON: &str = #graph_ron;
            #( #[doc = #shader_docs] pub const #consts: &str = #sources; )*
            /// Every WGSL module as (file name the graph refers to, source), in pass order.
            pub const SHADERS: &[(&str, &str)] = &[#( (#files, #consts), )*];
            /// The compiler's warnings, rendered.
            pub const WARNINGS: &[&str] = &[#( #warnings ),*];
            /// Bytes of the `Params` uniform (0: the technique has no runtime param).
            pub const PARAMS_SIZE: u32 = #params_size;

            /// Parse [`GRAPH_RON`] into the pass graph the runtime executes.
            pub fn graph() -> ::core::result::Result<#graph_crate::PassGraph, #graph_crate::GraphError> {
                #graph_crate::PassGraph::from_ron(GRAPH_RON)
            }

            /// [`SHADERS`] as owned pairs, as `Technique::new` takes them.
            pub fn shaders() -> ::std::vec::Vec<(::std::string::String, ::std::string::String)> {
                SHADERS.iter().map(|(f, s)| ((*f).to_string(), (*s).to_string())).collect()
            }

            /// Params fixed at compile time, with the values compiled in.
            pub mod fixed {
                #(#fixed)*
            }

            /// The technique's runtime params, laid out as the WGSL `Params` uniform
            /// (`@group(0) @binding(1)`); `Default` gives the technique's defaults.
            #[repr(C)]
            #[derive(Clone, Copy, Debug, PartialEq)]
            pub struct Params {
                #(#fields)*
                #pad_field
            }

            impl ::core::default::Default for Params {
                fn default() -> Self {
                    Params { #(#defaults)* }
                }
            }

            impl Params {
                /// Bytes of the uniform binding (a multiple of 16).
                pub const SIZE: usize = #size;
                /// The names of the fields, in uniform order.
                pub const NAMES: [&'static str; #n_uniform] = [#(#names),*];

                /// The uniform's contents, little-endian (padding zero).
                pub fn to_bytes(&self) -> [u8; Self::SIZE] {
                    #[allow(unused_mut)]
                    let mut b = [0u8; Self::SIZE];
                    #(#writes)*
                    b
                }

                /// (name, value) of every field, for `Params::set`.
                pub fn values(&self) -> [(&'static str, f64); #n_uniform] {
                    [#(#values)*]
                }
            }

            // The Rust layout must be the WGSL layout naga computes.
            const _: () = {
                #(#asserts)*
                ::core::assert!(::core::mem::size_of::<Params>() == #size, #size_msg);
                ::core::assert!(::core::mem::size_of::<Params>() == PARAMS_SIZE as usize, #graph_msg);
            };
        }
    })
}

fn param_doc(p: &ParamDecl) -> String {
    let mut s = format!("`{}`", p.name);
    if let Some(d) = &p.doc {
        s.push_str(": ");
        s.push_str(d);
    }
    s.push_str(&format!(" (technique default {}", p.value));
    if let Some((lo, hi)) = p.range {
        s.push_str(&format!(", range [{lo}, {hi}]"));
    }
    s.push(')');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    fn root() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
    }

    fn parse(t: TokenStream) -> TechniqueInput {
        syn::parse2(t).unwrap()
    }

    #[test]
    fn parses_options() {
        let i = parse(
            quote!(#[doc = "x"] pub(crate) mod pcf5 = "techniques/pcf.ron", set: { N = 5, "bias" = -0.25, x = true }, precision: { z = F16 }, graph: my::rt,),
        );
        assert_eq!(i.name, "pcf5");
        assert_eq!(i.path.value(), "techniques/pcf.ron");
        assert_eq!(
            i.set,
            vec![
                ("N".into(), "5".into()),
                ("bias".into(), "-0.25".into()),
                ("x".into(), "true".into())
            ]
        );
        assert_eq!(i.precision, vec![("z".into(), "F16".into())]);
        assert!(i.graph.is_some());
        assert_eq!(i.attrs.len(), 1);
    }

    #[test]
    fn refuses_bad_syntax() {
        for t in [
            quote!(pcf = "x.ron"),
            quote!(mod pcf "x.ron"),
            quote!(mod pcf = x),
            quote!(mod pcf = "x.ron", sett: {}),
            quote!(mod pcf = "x.ron", set: { N = 1 }, set: { N = 2 }),
        ] {
            assert!(syn::parse2::<TechniqueInput>(t).is_err());
        }
    }

    /// Every technique in `techniques/` (found, not listed: issue 52) expands to a module
    /// with its params' layout.
    #[test]
    fn every_bundled_technique_expands() {
        let mut names: Vec<String> = std::fs::read_dir(root().join("techniques"))
            .unwrap()
            .filter_map(|e| e.ok()?.file_name().to_str()?.strip_suffix(".ron").map(str::to_string))
            .collect();
        names.sort();
        assert!(names.len() >= 18, "{names:?}");
        for t in &names {
            let path = format!("techniques/{t}.ron");
            let out = expand_in(&parse(quote!(pub mod m = #path)), &root()).to_string();
            assert!(!out.contains("compile_error"), "{t}: {out}");
            assert!(out.contains("offset_of"), "{t}");
        }
    }

    #[test]
    fn pcf_layout_matches_graph() {
        let src = std::fs::read_to_string(root().join("techniques/pcf.ron")).unwrap();
        let c = sshc::compile_str(&src, &Default::default()).unwrap();
        let shade = c.shaders.iter().find(|(f, _)| f.ends_with("shade.wgsl")).unwrap();
        let l = params_layout(&shade.1).unwrap().unwrap();
        assert_eq!(l.span, 8);
        assert_eq!(l.uniform_size, 16);
        assert_eq!(l.members[1].0, "slope_bias");
        assert_eq!(l.members[1].1, 4);
    }

    #[test]
    fn errors_are_compile_errors() {
        let missing = expand_in(&parse(quote!(mod m = "no/such.ron")), &root()).to_string();
        assert!(missing.contains("compile_error") && missing.contains("no/such.ron"), "{missing}");
        let out = expand_in(&parse(quote!(mod m = "techniques/pcf.ron", set: { N = 99 })), &root()).to_string();
        assert!(out.contains("compile_error") && out.contains("techniques/pcf.ron:"), "{out}");
    }

    #[test]
    fn keywords_become_raw_identifiers() {
        assert_eq!(rust_ident("bias").to_string(), "bias");
        assert_eq!(rust_ident("type").to_string(), "r#type");
        assert_eq!(rust_ident("gen").to_string(), "r#gen");
        assert_eq!(rust_ident("self").to_string(), "self_");
    }
}
