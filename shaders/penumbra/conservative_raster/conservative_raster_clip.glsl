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
//   hooks:    none.
#ifndef PENUMBRA_CONSERVATIVE_RASTER_CLIP_GLSL
#define PENUMBRA_CONSERVATIVE_RASTER_CLIP_GLSL

bool penumbraConservativeInsideBox(vec2 frag_coord, vec4 box) {
    return all(greaterThanEqual(frag_coord, box.xy)) && all(lessThanEqual(frag_coord, box.zw));
}

#endif
