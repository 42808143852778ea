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

#endif
