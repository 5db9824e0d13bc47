//! Resources and their slots: a channel as stored in a resource as `lower` makes it
//! ([`Slot`]), as `analyse` finds it ([`SlotInfo`], [`Analysis`]) and as `pack` places it
//! in a texture ([`PlacedSlot`], [`Texture`]).

#[cfg(doc)]
use super::Layout;
use super::{ChannelId, Interval, PassId, ResId};
use crate::front::ast::Precision;
use crate::span::Span;
use std::collections::HashMap;

/// How a channel value is stored: `stored = (value - bias) * scale`, decoded as `stored / scale + bias`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Encode {
    pub bias: f64,
    pub scale: f64,
}

impl Encode {
    pub const IDENTITY: Encode = Encode { bias: 0.0, scale: 1.0 };

    pub fn is_identity(&self) -> bool {
        *self == Encode::IDENTITY
    }
}

/// What `analyse` found about one channel as stored in one resource.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SlotInfo {
    pub range: Interval,
    pub encode: Encode,
}

/// The product of `analyse`, a side table beside the IR (which `analyse` only reads):
/// range and storage encoding of every (resource, channel) slot as lowered, before
/// elimination drops any.
#[derive(Clone, Debug, Default)]
pub struct Analysis {
    pub slots: HashMap<(ResId, ChannelId), SlotInfo>,
}

impl Analysis {
    pub fn get(&self, r: ResId, c: ChannelId) -> Option<SlotInfo> {
        self.slots.get(&(r, c)).copied()
    }
}

/// One channel as stored in one resource, as `lower` knows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slot {
    pub channel: ChannelId,
    pub precision: Precision,
}

/// One channel as laid out by `pack`: its range and storage encoding (from the
/// [`Analysis`]) and its place, component `component` of layer `layer` of texture
/// `texture` of the resource.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedSlot {
    pub channel: ChannelId,
    pub precision: Precision,
    pub range: Interval,
    pub encode: Encode,
    pub texture: usize,
    pub layer: u32,
    pub component: u32,
}

impl PlacedSlot {
    /// Texture index, layer and component.
    pub fn place(&self) -> (usize, u32, u32) {
        (self.texture, self.layer, self.component)
    }
}

/// A slot as lowered or as laid out: what the IR's printer and validator read of both.
pub trait SlotView {
    fn channel(&self) -> ChannelId;
    fn precision(&self) -> Precision;
    /// The slot as laid out, after `pack`.
    fn placed(&self) -> Option<&PlacedSlot>;
}

impl SlotView for Slot {
    fn channel(&self) -> ChannelId {
        self.channel
    }
    fn precision(&self) -> Precision {
        self.precision
    }
    fn placed(&self) -> Option<&PlacedSlot> {
        None
    }
}

impl SlotView for PlacedSlot {
    fn channel(&self) -> ChannelId {
        self.channel
    }
    fn precision(&self) -> Precision {
        self.precision
    }
    fn placed(&self) -> Option<&PlacedSlot> {
        Some(self)
    }
}

/// One texture of a packed resource: all its channels of one precision.
#[derive(Clone, Debug)]
pub struct Texture {
    pub name: String,
    pub precision: Precision,
    /// Components per texel (1, 2 or 4).
    pub components: u32,
    pub layers: u32,
}

/// A resource whose slots are `S`: [`IrResource`] as lowered, [`PlacedResource`] as laid
/// out by `pack`.
#[derive(Clone, Debug)]
pub struct Resource<S> {
    pub name: String,
    pub slots: Vec<S>,
    pub writer: PassId,
    pub mips: bool,
    pub sat: bool,
    pub span: Span,
    /// False once dead-code elimination found no shaded pixel can reach it.
    pub live: bool,
    /// Set by `pack`.
    pub textures: Vec<Texture>,
}

/// A resource as `lower` left it.
pub type IrResource = Resource<Slot>;
/// A resource as `pack` laid it out (in [`Layout::resources`], indexed by [`ResId`]).
pub type PlacedResource = Resource<PlacedSlot>;

impl<S: SlotView> Resource<S> {
    pub fn slot_of(&self, c: ChannelId) -> Option<&S> {
        self.slots.iter().find(|s| s.channel() == c)
    }
}
