//! SPIR-V given to the driver as is ([`crate::SkyShader::from_spirv_exact`]) must number its
//! descriptors as wgpu's Vulkan back end lays them out, because nothing rewrites them on the way.
//!
//! wgpu-hal's Vulkan back end does not use a WGSL `@binding` as the Vulkan binding: it sorts a
//! bind group layout's entries by binding (wgpu-core's `EntryMap`) and numbers them 0, 1, 2, …
//! (`create_bind_group_layout`, `next_binding`); for a module it compiles itself, naga's SPIR-V
//! writer gets that numbering as its binding map. naga's SPIR-V written without the map keeps
//! the `@binding`s, which match only while a group's bindings are 0, 1, 2, … with no gap. A
//! material with textures but no scalar uniform has none at binding 0 (its block is absent), and
//! lavapipe then reads a descriptor that is not there: measured, it dies with SIGBUS compiling
//! the pipeline. [`vulkan_bindings`] renumbers the `Binding` decorations the same way.

use crate::bindings::Binding;

const OP_DECORATE: u32 = 71;
const DECORATION_BINDING: u32 = 33;
const DECORATION_DESCRIPTOR_SET: u32 = 34;

/// `spirv` with every `Binding` decoration replaced by the resource's rank among its group's
/// `layout` bindings in ascending order (its set's number unchanged). Errors name a resource the
/// layout lacks.
pub(crate) fn vulkan_bindings(spirv: &[u32], layout: &[Binding]) -> Result<Vec<u32>, String> {
    let mut words = spirv.to_vec();
    // (instruction start, opcode, length) after the five header words.
    let mut decorations = Vec::new();
    let mut at = 5;
    while at < words.len() {
        let (len, opcode) = ((words[at] >> 16) as usize, words[at] & 0xffff);
        if len == 0 || at + len > words.len() {
            return Err("the SPIR-V binary is truncated".into());
        }
        if opcode == OP_DECORATE && len == 4 {
            decorations.push(at);
        }
        at += len;
    }
    let set_of = |id: u32| {
        decorations
            .iter()
            .find(|&&d| words[d + 1] == id && words[d + 2] == DECORATION_DESCRIPTOR_SET)
            .map(|&d| words[d + 3])
    };
    let mut renumbered = Vec::new();
    for &d in &decorations {
        if words[d + 2] != DECORATION_BINDING {
            continue;
        }
        let (id, binding) = (words[d + 1], words[d + 3]);
        let group = set_of(id).ok_or_else(|| format!("resource %{id} has a Binding but no DescriptorSet"))?;
        let mut in_group: Vec<u32> = layout.iter().filter(|b| b.group == group).map(|b| b.binding).collect();
        in_group.sort_unstable();
        in_group.dedup();
        let rank = in_group
            .iter()
            .position(|&b| b == binding)
            .ok_or_else(|| format!("the layout has no @group({group}) @binding({binding})"))?;
        renumbered.push((d + 3, rank as u32));
    }
    for (word, value) in renumbered {
        words[word] = value;
    }
    Ok(words)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bindings::BindingKind;

    fn binding(group: u32, binding: u32) -> Binding {
        Binding { name: format!("g{group}b{binding}"), group, binding, kind: BindingKind::Uniform { size: 16 } }
    }

    #[test]
    fn bindings_become_ranks_within_their_group() {
        // Header, then: %7 set 1 binding 2; %8 set 1 binding 1; %9 set 0 binding 0.
        let decorate = |id: u32, decoration: u32, value: u32| [(4 << 16) | OP_DECORATE, id, decoration, value];
        let mut spirv = vec![0x0723_0203, 0x0001_0300, 0, 10, 0];
        for (id, set, b) in [(7, 1, 2), (8, 1, 1), (9, 0, 0)] {
            spirv.extend(decorate(id, DECORATION_DESCRIPTOR_SET, set));
            spirv.extend(decorate(id, DECORATION_BINDING, b));
        }
        let layout = [binding(0, 0), binding(1, 2), binding(1, 1)];
        let out = vulkan_bindings(&spirv, &layout).expect("every resource is in the layout");
        let value = |id: u32| {
            out[5..]
                .chunks(4)
                .find(|i| i.len() == 4 && i[1] == id && i[2] == DECORATION_BINDING)
                .map(|i| i[3])
                .expect("decorated")
        };
        assert_eq!((value(7), value(8), value(9)), (1, 0, 0));
        assert!(vulkan_bindings(&spirv, &[binding(0, 0), binding(1, 2)]).is_err(), "binding 1 of group 1 is missing");
    }
}
