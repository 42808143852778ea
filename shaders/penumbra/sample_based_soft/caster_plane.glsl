// penumbra — sample-based soft shadows: fp64 helpers and the caster's supporting plane against the
// light, for the skips (penumbra::SoftSkips). GLSL twin of detail::soft::casterPlane,
// casterFacesAway and casterPlaneCuts (include/penumbra/pipelines/sample_based_soft.hpp), step for
// step: normal = (v1 - v0) x (v2 - v0) in double from the float vertices; a signed distance
// dot(normal, x - v0) / |normal| is off by at most (dn + 4 eps |normal|) |x - v0| / |normal|,
// dn = 8 eps |v1 - v0| |v2 - v0|, shrunk by another 1e-9 relative.
#ifndef PENUMBRA_SBS_CASTER_PLANE_GLSL
#define PENUMBRA_SBS_CASTER_PLANE_GLSL

const double kPenumbraSbsEpsilon = 1.1102230246251565404e-16LF;  // 2^-53

double penumbraSbsMaxAbs(dvec3 v) {
    const dvec3 m = abs(v);
    return max(m.x, max(m.y, m.z));
}
double penumbraSbsDot(dvec3 a, dvec3 b) {
    precise double r = (a.x * b.x + a.y * b.y) + a.z * b.z;
    return r;
}
dvec3 penumbraSbsCross(dvec3 a, dvec3 b) {
    precise dvec3 r = dvec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    return r;
}
double penumbraSbsLength(dvec3 a) { return sqrt(penumbraSbsDot(a, a)); }

struct PenumbraSbsCasterPlane {
    dvec3 v0, normal;
    double normal_length;
    double error_per_unit;   // (dn + 4 eps |normal|) / |normal|
    double light_side;       // dot(normal, centre - v0)
    double light_clearance;  // every light point on light_side's side, at least this far (<= 0: unproven)
};

PenumbraSbsCasterPlane penumbraSbsCasterPlane(dvec3 v0, dvec3 v1, dvec3 v2, dvec3 centre, double light_reach) {
    PenumbraSbsCasterPlane c = PenumbraSbsCasterPlane(v0, dvec3(0.0LF), 0.0LF, 0.0LF, 0.0LF, 0.0LF);
    const dvec3 e0 = v1 - v0, e1 = v2 - v0;
    c.normal = penumbraSbsCross(e0, e1);
    c.normal_length = penumbraSbsLength(c.normal);
    if (!(c.normal_length > 0.0LF) || !(c.normal_length < 1e300LF)) return c;
    precise double dn = 8.0LF * kPenumbraSbsEpsilon * penumbraSbsLength(e0) * penumbraSbsLength(e1);
    precise double per_unit = (dn + 4.0LF * kPenumbraSbsEpsilon * c.normal_length) / c.normal_length;
    c.error_per_unit = per_unit;
    const dvec3 to_centre = centre - v0;
    c.light_side = penumbraSbsDot(c.normal, to_centre);
    precise double clearance =
        (abs(c.light_side) / c.normal_length - c.error_per_unit * penumbraSbsLength(to_centre)) * (1.0LF - 1e-9LF) - light_reach;
    c.light_clearance = clearance;
    return c;
}

// The whole light strictly behind the plane: a closed caster's triangle that cannot block.
bool penumbraSbsCasterFacesAway(PenumbraSbsCasterPlane c) { return c.light_side < 0.0LF && c.light_clearance > 0.0LF; }

// p strictly on the plane's positive side (outside a closed mesh's face): a segment from p to a
// light point the face faces never crosses its plane.
bool penumbraSbsCasterPlaneOutside(PenumbraSbsCasterPlane c, dvec3 p) {
    if (!(c.normal_length > 0.0LF)) return false;
    const dvec3 to_p = p - c.v0;
    const double side = penumbraSbsDot(c.normal, to_p);
    precise double clearance = (side / c.normal_length - c.error_per_unit * penumbraSbsLength(to_p)) * (1.0LF - 1e-9LF);
    return side > 0.0LF && clearance > 0.0LF;
}

// p and the whole light strictly on one side of the plane, both farther than `reach`.
bool penumbraSbsCasterPlaneCuts(PenumbraSbsCasterPlane c, dvec3 p, double reach) {
    if (!(c.light_clearance > reach)) return false;
    const dvec3 to_p = p - c.v0;
    const double side = penumbraSbsDot(c.normal, to_p);
    precise double clearance = (abs(side) / c.normal_length - c.error_per_unit * penumbraSbsLength(to_p)) * (1.0LF - 1e-9LF);
    return clearance > reach && (side > 0.0LF) == (c.light_side > 0.0LF);
}

// SoftSkips::silhouettes, the coplanar rule's open edges (detail::soft::coplanarOpen, step for
// step; docs/design.md, Silhouettes): true when the oracle may ignore T for some light sample of
// p's (rule 2: p, or the sample, within coplanar_epsilon * scale of T) while a segment from p to
// the light could cross T's plane where another triangle is counted. distance2: p to T squared;
// light_distance2: the light's centre to T squared. False needs the whole light strictly on one
// side of T's plane and p either strictly on that side too (no segment meets the plane) or so
// close to it that every segment meets the plane within epsilon * s_min of p (s_min <= |l - p|_inf
// for every light point l), where every triangle is ignored for every sample. scene_extent: the
// oracle's E; s_min and s_max capped at it as the oracle caps |l - p|_inf (monotone: still bounds).
bool penumbraSbsCoplanarOpen(PenumbraSbsCasterPlane c, dvec3 p, double scale_v, double distance2, double light_distance2,
                             dvec3 centre, double light_reach, double epsilon, double scene_extent) {
    const double centre_reach = penumbraSbsMaxAbs(centre - p);
    const double s_min = min(max(0.0LF, centre_reach - light_reach), scene_extent);
    const double s_max = min(centre_reach + light_reach, scene_extent);
    precise double reach = epsilon * max(scale_v, s_max);
    precise double light_near = reach + light_reach;
    const bool p_near = !(distance2 > reach * reach * (1.0LF + 1e-9LF));
    const bool light_near_t = !(light_distance2 > light_near * light_near * (1.0LF + 1e-9LF));
    if (!p_near && !light_near_t) return false;  // T is counted for every light sample
    if (light_near_t || !(c.normal_length > 0.0LF) || !(c.light_clearance > 0.0LF)) return true;
    const dvec3 to_p = p - c.v0;
    const double side = penumbraSbsDot(c.normal, to_p);
    precise double error = c.error_per_unit * penumbraSbsLength(to_p);
    precise double distance = abs(side) / c.normal_length;
    precise double clearance = (distance - error) * (1.0LF - 1e-9LF);
    if ((side > 0.0LF) == (c.light_side > 0.0LF) && clearance > 0.0LF) return false;  // p on the light's side
    // The segment to a light point l meets the plane at d |l - p| / (d + h) <= d |l - p| / clearance from p.
    precise double d_hi = (distance + error) * (1.0LF + 1e-9LF);
    precise double length_hi = (penumbraSbsLength(centre - p) + light_reach) * (1.0LF + 1e-9LF);
    precise double r_min = epsilon * s_min * (1.0LF - 1e-6LF);
    return !(d_hi * length_hi < r_min * c.light_clearance);
}

#endif
