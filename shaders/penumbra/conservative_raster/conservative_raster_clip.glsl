// penumbra — fragment-side clip of conservative coverage to the triangle's pixel-expanded bounding
// box (sintorn2008 §3.2 / Fig. 4: "fragments outside the triangle's pixel-expanded bounding box can
// be discarded"). The fixed 6-vertex hull over-covers up to one pixel past acute (case iii)
// corners; most of that lies outside this box.
//
// Integration summary
//   needs:    the flat vec4 `box` the geometry stage handed to PENUMBRA_CONSERVATIVE_EMIT_VERTEX
//             (window pixels: xmin, ymin, xmax, ymax; already expanded by h = 0.5 + margin).
//   call:     if (!penumbraConservativeInsideBox(gl_FragCoord.xy, box)) discard;
//   keeps:    every fragment whose pixel's closed square can touch the triangle: such a pixel's
//             centre lies within 0.5 of the triangle's bounding box, so inside `box`.
//   compute:  ivec4 penumbraConservativeBoxPixels(box, viewport): the pixel range to visit
//             without rasterizing, for penumbraConservativeEmit built with
//             PENUMBRA_CONSERVATIVE_BOX_ONLY (the box, no hull).
//   hooks:    none.
#ifndef PENUMBRA_CONSERVATIVE_RASTER_CLIP_GLSL
#define PENUMBRA_CONSERVATIVE_RASTER_CLIP_GLSL

bool penumbraConservativeInsideBox(vec2 frag_coord, vec4 box) {
    return all(greaterThanEqual(frag_coord, box.xy)) && all(lessThanEqual(frag_coord, box.zw));
}

// Coverage without rasterizing (the compute light passes): the pixels (x0, y0) .. (x1, y1),
// inclusive, of the viewport `viewport` (x, y, width, height) whose centres `box` may hold — every
// pixel penumbraConservativeInsideBox keeps, one more on each side (no rounding argument needed),
// clipped to the viewport; x1 < x0 or y1 < y0 when none. Test each pixel's centre with
// penumbraConservativeInsideBox to visit exactly the fragment stage's pixels. `box` comes from a
// hull that was not dropped: it lies within the guard band, so its coordinates convert to int.
// CPU twin: penumbra::conservativeBoxPixels.
ivec4 penumbraConservativeBoxPixels(vec4 box, ivec4 viewport) {
    const ivec2 lo = max(ivec2(floor(box.xy)) - 1, viewport.xy);
    const ivec2 hi = min(ivec2(floor(box.zw)) + 1, viewport.xy + viewport.zw - 1);
    return ivec4(lo, hi);
}

#endif
