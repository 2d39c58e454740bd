//! The world's bind group (group 0 of every pass): its logical buffers in binding order
//! ([`BUFFERS`]), how they are split across bindings ([`Split`]), and the storage binding
//! that every binding of every pass is ([`storage_entry`]).
//!
//! It lies beneath [`super::GpuWorld`], which allocates and binds the buffers, and beneath
//! [`super::shaders`], which declares them for WGSL.

/// The logical storage buffers of group 0, in binding order, with their accessor names.
pub const BUFFERS: [(&str, &str); 8] = [
    ("chunks", "chunk_word"),
    ("blocks", "block_word"),
    ("voxels", "voxel_word"),
    ("materials", "material_word"),
    ("entity_types", "entity_type_word"),
    ("entity_instances", "instance_word"),
    // The hierarchy over the instances' world boxes, derived from the instance buffer
    // (naadf_world::entity::bvh), not mirrored.
    ("entity_hierarchy", "hierarchy_word"),
    // The structure a comparison traversal walks instead of the world's hierarchy: the
    // dense grid, an SVO, an SVDAG or a hybrid format (whichever was uploaded last).
    ("structure", "structure_word"),
];

/// How the buffers of group 0 are split: each logical buffer has `parts[i]` bindings of
/// `1 << part_shift` words each (the last one may be shorter).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Split {
    /// log2 of the words per binding.
    pub part_shift: u32,
    /// Bindings per logical buffer, in the order of the world's buffers (`BUFFERS`).
    pub parts: [u32; 8],
}

impl Split {
    /// Bindings of the world's buffer parts in group 0 (bindings 1, 2, …; `world_info` is
    /// binding 0).
    pub fn bindings(&self) -> u32 {
        self.parts.iter().sum()
    }

    /// Storage bindings of group 0 in all: `world_info` and the buffer parts.
    pub fn storage_bindings(&self) -> u32 {
        1 + self.bindings()
    }
}

/// A compute-stage storage-buffer binding; every binding of every pass is one (see
/// [`super::Gpu::params`] for why none is a uniform buffer).
pub(crate) fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}
