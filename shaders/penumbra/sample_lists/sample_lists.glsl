// penumbra — walking a light texel's list of view samples from the integrator's own light pass
// (sintorn2008 §3, Fig. 3: "An offset and length per pixel allow to access the sequentially
// stored lists"; §3.2: "For each pixel intersected by a triangle t, the local list is traversed
// and each view-sample is tested").
//
// Hooks the integrator defines before including this file (it owns the buffers and bindings):
//   PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list)     -> uint, counts[list]   (list = y * W + x)
//   PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list)    -> uint, offsets[list]
//   PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot)  -> vec4, list_positions[slot] (xyz world, w = 1)
//   PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot)        -> uint, list_ids[slot]  (the view-sample id)
//   PENUMBRA_SAMPLE_LISTS_GRID_WIDTH           -> uint expression, the grid width W
// Typical loop, in a fragment shader rasterized into the W x H grid:
//   uvec2 range = penumbraSampleListsRange(ivec2(gl_FragCoord.xy));
//   for (uint slot = range.x; slot < range.x + range.y; ++slot) {
//       vec3 p = penumbraSampleListsPosition(slot); ... penumbraSampleListsSetShadowBit(slot, 0u);
//   }
// (shadow bits: penumbra/sample_lists/shadow_bits.glsl). Long lists: walk them in blocks over
// several passes (§3.1: "If more view-samples are in a list, blocks of 1024 samples are treated,
// and multi-pass rendering is used"), pass b using penumbraSampleListsBlock(texel, b, size);
// ceil(max_list_length / size) passes cover every list (max_list_length: the Fig. 9 statistics).
// Drivers cap work per invocation: llvmpipe ends any invocation's loops after 65 535 iterations in
// total, so keep size * (iterations per sample) below that there.
#ifndef PENUMBRA_SAMPLE_LISTS_GLSL
#define PENUMBRA_SAMPLE_LISTS_GLSL

#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_COUNT
#error "penumbra/sample_lists/sample_lists.glsl: define the hook PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list) -> uint"
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET
#error "penumbra/sample_lists/sample_lists.glsl: define the hook PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list) -> uint"
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_POSITION
#error "penumbra/sample_lists/sample_lists.glsl: define the hook PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot) -> vec4"
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_LOAD_ID
#error "penumbra/sample_lists/sample_lists.glsl: define the hook PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot) -> uint"
#endif
#ifndef PENUMBRA_SAMPLE_LISTS_GRID_WIDTH
#error "penumbra/sample_lists/sample_lists.glsl: define the hook PENUMBRA_SAMPLE_LISTS_GRID_WIDTH (uint grid width W)"
#endif

// The list index of a texel: lists are stored row by row (§3.1: "interprets the 2D texture as a
// 1D array (line by line)").
uint penumbraSampleListsIndex(ivec2 texel) {
    return uint(texel.y) * uint(PENUMBRA_SAMPLE_LISTS_GRID_WIDTH) + uint(texel.x);
}

// (first slot, length) of the texel's list; its slots are first .. first + length - 1.
uvec2 penumbraSampleListsRange(ivec2 texel) {
    const uint list = penumbraSampleListsIndex(texel);
    return uvec2(PENUMBRA_SAMPLE_LISTS_LOAD_OFFSET(list), PENUMBRA_SAMPLE_LISTS_LOAD_COUNT(list));
}

// (first slot, length) of block `block` of the texel's list: slots block * size .. block * size +
// size - 1 of the list, clipped to its length (length 0 past its end). Needs block * size < 2^32.
uvec2 penumbraSampleListsBlock(ivec2 texel, uint block, uint size) {
    const uvec2 range = penumbraSampleListsRange(texel);
    const uint first = block * size;
    if (first >= range.y) return uvec2(range.x + range.y, 0u);
    return uvec2(range.x + first, min(size, range.y - first));
}

// World position of the view sample stored in `slot`.
vec3 penumbraSampleListsPosition(uint slot) {
    return PENUMBRA_SAMPLE_LISTS_LOAD_POSITION(slot).xyz;
}

// View-sample id of `slot` (buffer input: its index; depth input: y * view width + x).
uint penumbraSampleListsId(uint slot) {
    return PENUMBRA_SAMPLE_LISTS_LOAD_ID(slot);
}

#endif
