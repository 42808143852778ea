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
// The hull's region without rasterizing it, for an unclipped triangle (p0, p1, p2 counter-
// clockwise, viewport-relative pixels, dilated by h): is `centre` (viewport-relative) inside all
// three edges moved out by the square [-h, h]^2? With the box test this is the exact hull, so it
// keeps every pixel a fragment stage would see that can touch the triangle. In double: edge
// vectors and differences of floats are exact, each side test rounds once. CPU twin:
// penumbra::conservativeInsideDilatedTriangle.
bool penumbraConservativeInsideDilatedTriangle(vec2 centre, vec2 p0, vec2 p1, vec2 p2, float h) {
    const dvec2 p[3] = dvec2[3](dvec2(p0), dvec2(p1), dvec2(p2));
    bool inside = true;
    for (int i = 0; i < 3; ++i) {
        const dvec2 a = p[i], b = p[i == 2 ? 0 : i + 1];
        const dvec2 n = dvec2(b.y - a.y, a.x - b.x);  // outward normal of a counter-clockwise edge
        precise double side = n.x * (double(centre.x) - a.x) + n.y * (double(centre.y) - a.y);
        precise double support = double(h) * (abs(n.x) + abs(n.y));
        inside = inside && !(side > support * (1.0LF + 1e-9LF));
    }
    return inside;
}

// Tiles of pixels at once: false only when no point of the rectangle [lo, hi] (e.g. the centres
// of a tile's pixels, viewport-relative) passes penumbraConservativeInsideDilatedTriangle with the
// same arguments: a point passes an edge where its side value is small enough, and an edge's
// smallest side value over the rectangle is at the corner its normal points away from (every
// value computed as that function does). A rectangle no point of which passes some edge holds no
// passing point; the converse need not hold (then the pixels are tested one by one).
bool penumbraConservativeRectMeetsDilatedTriangle(vec2 lo, vec2 hi, vec2 p0, vec2 p1, vec2 p2, float h) {
    const dvec2 p[3] = dvec2[3](dvec2(p0), dvec2(p1), dvec2(p2));
    bool meets = true;
    for (int i = 0; i < 3; ++i) {
        const dvec2 a = p[i], b = p[i == 2 ? 0 : i + 1];
        const dvec2 n = dvec2(b.y - a.y, a.x - b.x);
        const vec2 corner = vec2(n.x > 0.0 ? lo.x : hi.x, n.y > 0.0 ? lo.y : hi.y);
        precise double side = n.x * (double(corner.x) - a.x) + n.y * (double(corner.y) - a.y);
        precise double support = double(h) * (abs(n.x) + abs(n.y));
        meets = meets && !(side > support * (1.0LF + 1e-9LF));
    }
    return meets;
}

ivec4 penumbraConservativeBoxPixels(vec4 box, ivec4 viewport) {
    const ivec2 lo = max(ivec2(floor(box.xy)) - 1, viewport.xy);
    const ivec2 hi = min(ivec2(floor(box.zw)) + 1, viewport.xy + viewport.zw - 1);
    return ivec4(lo, hi);
}

#endif
