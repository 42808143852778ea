// penumbra — shadow-edge stencil (galoppo2010): the double arithmetic of the sub-samples, the light
// grid binning and the footprint-vs-shadow-volume sphere test, step for step the operations of
// include/penumbra/shadow_edge_stencil.hpp (detail::aa*): fixed grouping, `precise` (no FMA), so
// the bits match the CPU twin wherever fp64 +, -, *, / and sqrt are correctly rounded. No bindings,
// no main: entry shaders pass the data in.
#ifndef PENUMBRA_SHADOW_EDGE_STENCIL_GLSL
#define PENUMBRA_SHADOW_EDGE_STENCIL_GLSL

#define PENUMBRA_AA_MAX_STRETCH 8.0lf

double penumbraAaDot(dvec3 a, dvec3 b) {
    precise double d = (a.x * b.x + a.y * b.y) + a.z * b.z;
    return d;
}

double penumbraAaLength(dvec3 v) { return sqrt(penumbraAaDot(v, v)); }

dvec3 penumbraAaCross(dvec3 a, dvec3 b) {
    precise dvec3 c = dvec3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
    return c;
}

dvec3 penumbraAaAxpy(dvec3 o, double t, dvec3 d) {
    precise dvec3 r = dvec3(o.x + t * d.x, o.y + t * d.y, o.z + t * d.z);
    return r;
}

// m * v grouped as GLM does: (m0 x + m1 y) + (m2 z + m3 w); m given as four columns.
dvec4 penumbraAaTransform(dvec4 m0, dvec4 m1, dvec4 m2, dvec4 m3, dvec4 v) {
    precise dvec4 r = (m0 * v.x + m1 * v.y) + (m2 * v.z + m3 * v.w);
    return r;
}

dvec3 penumbraAaUnproject(dvec4 m0, dvec4 m1, dvec4 m2, dvec4 m3, double x, double y, double z) {
    dvec4 h = penumbraAaTransform(m0, m1, m2, m3, dvec4(x, y, z, 1.0lf));
    precise dvec3 r = dvec3(h.x / h.w, h.y / h.w, h.z / h.w);
    return r;
}

double penumbraAaNdc(double p, uint size) {
    precise double r = (p / double(size)) * 2.0lf - 1.0lf;
    return r;
}

double penumbraAaGrid(double x, double w, uint size) {
    precise double r = ((x / w) * 0.5lf + 0.5lf) * double(size);
    return r;
}

// The centre's parameter on its pixel-centre ray (detail::aaCentreParameter).
double penumbraAaCentreParameter(dvec4 m0, dvec4 m1, dvec4 m2, dvec4 m3, double z_near, uvec2 size, uvec2 pixel, dvec3 c) {
    precise double px = double(pixel.x) + 0.5lf;
    precise double py = double(pixel.y) + 0.5lf;
    double nx = penumbraAaNdc(px, size.x), ny = penumbraAaNdc(py, size.y);
    dvec3 o = penumbraAaUnproject(m0, m1, m2, m3, nx, ny, z_near);
    precise dvec3 d = penumbraAaUnproject(m0, m1, m2, m3, nx, ny, 1.0lf) - o;
    precise dvec3 co = c - o;
    precise double s = penumbraAaDot(co, d) / penumbraAaDot(d, d);
    return s;
}

// The sub-sample at `off` on the plane (c, n) (detail::aaSubSample); flags: 1 stretched, 2 fallback.
vec4 penumbraAaSubSample(dvec4 m0, dvec4 m1, dvec4 m2, dvec4 m3, double z_near, uvec2 size, uvec2 pixel, dvec3 c, dvec3 n,
                         vec2 off, double s0, out uint flags) {
    precise double px = (double(pixel.x) + 0.5lf) + double(off.x);
    precise double py = (double(pixel.y) + 0.5lf) + double(off.y);
    double nx = penumbraAaNdc(px, size.x), ny = penumbraAaNdc(py, size.y);
    dvec3 o = penumbraAaUnproject(m0, m1, m2, m3, nx, ny, z_near);
    precise dvec3 d = penumbraAaUnproject(m0, m1, m2, m3, nx, ny, 1.0lf) - o;
    double dn = penumbraAaDot(n, d);
    precise dvec3 co = c - o;
    precise double t = penumbraAaDot(n, co) / dn;
    flags = 0u;
    dvec3 q = c;
    if (dn != 0.0lf && !isinf(t) && !isnan(t) && t > 0.0lf) {
        q = penumbraAaAxpy(o, t, d);
        precise dvec3 f = penumbraAaAxpy(o, s0, d) - c;
        double fronto = penumbraAaLength(f);
        precise double reach = PENUMBRA_AA_MAX_STRETCH * fronto;
        precise dvec3 qc = q - c;
        double dist = penumbraAaLength(qc);
        if (dist > reach && dist > 0.0lf) {
            precise double k = reach / dist;
            q = penumbraAaAxpy(c, k, qc);
            flags = 1u;
        }
    } else {
        flags = 2u;
    }
    return vec4(vec3(q), 1.0);
}

// The sample lists' light-facing test (classifySample), in float, same order.
bool penumbraAaBackFacing(vec4 light, vec4 p, vec3 n) {
    precise float lx = light.w == 0.0 ? light.x : light.x - p.x;
    precise float ly = light.w == 0.0 ? light.y : light.y - p.y;
    precise float lz = light.w == 0.0 ? light.z : light.z - p.z;
    precise float facing = n.x * lx + n.y * ly;
    precise float facing2 = facing + n.z * lz;
    return !(facing2 > 0.0);
}

// A triangle's shadow volume (detail::aaShadowVolume): planes (unit normal, offset), positive inside.
struct PenumbraAaVolume {
    dvec4 planes[5];
    int count;
    bool valid;
    bool blocks_nothing;
};

PenumbraAaVolume penumbraAaShadowVolume(dvec3 a, dvec3 b, dvec3 c, vec4 light, double reach) {
    PenumbraAaVolume v;
    v.count = 0;
    v.valid = false;
    v.blocks_nothing = false;
    for (int k = 0; k < 5; ++k) v.planes[k] = dvec4(0.0lf);
    bool point = light.w != 0.0;
    dvec3 l = dvec3(light.xyz);
    precise dvec3 ab = b - a;
    precise dvec3 ac = c - a;
    dvec3 nt = penumbraAaCross(ab, ac);
    double nt_len = penumbraAaLength(nt);
    if (!(nt_len > 0.0lf)) return v;
    precise dvec3 u = nt / nt_len;
    dvec3 corners[3] = dvec3[3](a, b, c);
    for (int e = 0; e < 3; ++e) {
        dvec3 p0 = corners[e], p1 = corners[(e + 1) % 3], opposite = corners[(e + 2) % 3];
        precise dvec3 p0l = p0 - l;
        precise dvec3 p1l = p1 - l;
        precise dvec3 p10 = p1 - p0;
        dvec3 m = point ? penumbraAaCross(p0l, p1l) : penumbraAaCross(p10, l);
        double len = penumbraAaLength(m);
        if (!(len > 0.0lf)) return v;
        precise dvec3 mu = m / len;
        precise dvec3 op = opposite - p0;
        double side = penumbraAaDot(mu, op);
        if (side == 0.0lf) return v;
        if (side < 0.0lf) mu = -mu;
        v.planes[e] = dvec4(mu, -penumbraAaDot(mu, p0));
    }
    if (point) {
        precise dvec3 la = l - a;
        double dl = penumbraAaDot(u, la);
        if (dl == 0.0lf) {
            v.blocks_nothing = true;
            return v;
        }
        dvec3 beyond = dl > 0.0lf ? -u : u;
        v.planes[3] = dvec4(beyond, -penumbraAaDot(beyond, a));
        v.count = 4;
    } else {
        double dd = penumbraAaDot(u, l);
        if (dd == 0.0lf) {
            v.blocks_nothing = true;
            return v;
        }
        dvec3 beyond = dd > 0.0lf ? -u : u;
        v.planes[3] = dvec4(beyond, -penumbraAaDot(beyond, a));
        precise double w4 = penumbraAaDot(beyond, a) + reach * abs(dd);
        v.planes[4] = dvec4(-beyond, w4);
        v.count = 5;
    }
    v.valid = true;
    return v;
}

double penumbraAaPlaneDistance(dvec4 plane, dvec3 p) {
    precise double d = penumbraAaDot(plane.xyz, p) + plane.w;
    return d;
}

// detail::aaSphereMargin.
double penumbraAaSphereMargin(dvec3 a, dvec3 b, dvec3 c, dvec3 q, double r, vec4 light, double reach, double eps) {
    precise dvec3 ba = b - a;
    precise dvec3 ca = c - a;
    precise dvec3 cb = c - b;
    double tri = max(penumbraAaLength(ba), max(penumbraAaLength(ca), penumbraAaLength(cb)));
    precise dvec3 lq = dvec3(light.xyz) - q;
    precise double to_light_dir = reach * penumbraAaLength(dvec3(light.xyz));
    double to_light = light.w != 0.0 ? penumbraAaLength(lq) : to_light_dir;
    precise dvec3 aq = a - q;
    precise double scale = ((penumbraAaLength(aq) + tri) + r) + to_light;
    precise double margin = r + (2.0lf * eps + 1e-9lf) * scale;
    return margin;
}

// detail::aaSphereClass: -1 blocks none, 1 blocks all, 0 undecided.
int penumbraAaSphereClass(PenumbraAaVolume v, dvec3 q, double margin, vec4 light) {
    if (!v.valid) return 0;
    bool all_inside = true;
    for (int k = 0; k < v.count; ++k) {
        double d = penumbraAaPlaneDistance(v.planes[k], q);
        if (d < -margin) return -1;
        if (!(d > margin)) all_inside = false;
    }
    if (all_inside && light.w != 0.0 && abs(penumbraAaPlaneDistance(v.planes[3], dvec3(light.xyz))) <= margin) return 0;
    return all_inside ? 1 : 0;
}

vec2 penumbraAaOffset(vec4 offsets[PENUMBRA_AA_MAX_SAMPLES / 2], uint k) {
    vec4 pair = offsets[k >> 1];
    return (k & 1u) == 0u ? pair.xy : pair.zw;
}

// ---- The Chebyshev stencil's moment map (detail::aaDepthTriangle, aaDepthTexel, aaLightDepth).

double penumbraAaLightDepth(dvec4 c, bool perspective) {
    precise double d = perspective ? -1.0lf / c.w : c.z / c.w;
    return d;
}

// Float depths as uints that order like the floats (atomicMin on the bits).
uint penumbraAaOrderedBits(float f) {
    uint u = floatBitsToUint(f);
    return (u & 0x80000000u) != 0u ? ~u : (u | 0x80000000u);
}
float penumbraAaFromOrderedBits(uint e) {
    return uintBitsToFloat((e & 0x80000000u) != 0u ? (e & 0x7fffffffu) : ~e);
}

struct PenumbraAaDepthTriangle {
    dvec3 s[4];
    int count;
    double ga, gb, g0, dmin, dmax, orientation;
    dvec2 lo, hi;
};

bool penumbraAaDepthTriangle(dvec4 m0, dvec4 m1, dvec4 m2, dvec4 m3, dvec3 p0, dvec3 p1, dvec3 p2, uint width, uint height,
                             bool perspective, out PenumbraAaDepthTriangle t) {
    dvec4 h[3] = dvec4[3](penumbraAaTransform(m0, m1, m2, m3, dvec4(p0, 1.0lf)), penumbraAaTransform(m0, m1, m2, m3, dvec4(p1, 1.0lf)),
                          penumbraAaTransform(m0, m1, m2, m3, dvec4(p2, 1.0lf)));
    t.count = 0;
    for (int k = 0; k < 4; ++k) t.s[k] = dvec3(0.0lf);
    t.ga = 0.0lf;
    t.gb = 0.0lf;
    t.g0 = 0.0lf;
    t.dmin = 0.0lf;
    t.dmax = 0.0lf;
    t.orientation = 1.0lf;
    t.lo = dvec2(0.0lf);
    t.hi = dvec2(0.0lf);
    double w_max = max(h[0].w, max(h[1].w, h[2].w));
    if (!(w_max > 0.0lf)) return false;
    precise double w_scaled = 1e-4lf * w_max;
    double w_min = perspective ? w_scaled : -1e300lf;
    for (int k = 0; k < 3; ++k) {
        dvec4 a = h[k], b = h[(k + 1) % 3];
        if (a.w >= w_min) {
            t.s[t.count] = dvec3(penumbraAaGrid(a.x, a.w, width), penumbraAaGrid(a.y, a.w, height), penumbraAaLightDepth(a, perspective));
            ++t.count;
        }
        if ((a.w >= w_min) != (b.w >= w_min)) {
            precise double f = (w_min - a.w) / (b.w - a.w);
            precise dvec4 c = dvec4(a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.z + (b.z - a.z) * f, a.w + (b.w - a.w) * f);
            t.s[t.count] = dvec3(penumbraAaGrid(c.x, c.w, width), penumbraAaGrid(c.y, c.w, height), penumbraAaLightDepth(c, perspective));
            ++t.count;
        }
    }
    if (t.count < 3) return false;
    t.dmin = 1e300lf;
    t.dmax = -1e300lf;
    t.lo = dvec2(1e300lf);
    t.hi = dvec2(-1e300lf);
    double area = 0.0lf;
    for (int j = 0; j < t.count; ++j) {
        dvec3 q = t.s[(j + 1) % t.count];
        t.dmin = min(t.dmin, t.s[j].z);
        t.dmax = max(t.dmax, t.s[j].z);
        t.lo = min(t.lo, t.s[j].xy);
        t.hi = max(t.hi, t.s[j].xy);
        precise double term = t.s[j].x * q.y - q.x * t.s[j].y;
        precise double next = area + term;
        area = next;
    }
    t.orientation = area > 0.0lf ? 1.0lf : -1.0lf;
    double best = 0.0lf;
    t.g0 = t.dmin;
    for (int j = 1; j + 1 < t.count; ++j) {
        precise dvec3 e1 = t.s[j] - t.s[0];
        precise dvec3 e2 = t.s[j + 1] - t.s[0];
        precise double det = e1.x * e2.y - e1.y * e2.x;
        if (abs(det) > best) {
            best = abs(det);
            precise double ga = (e1.z * e2.y - e2.z * e1.y) / det;
            precise double gb = (e2.z * e1.x - e1.z * e2.x) / det;
            precise double g0 = (t.s[0].z - ga * t.s[0].x) - gb * t.s[0].y;
            t.ga = ga;
            t.gb = gb;
            t.g0 = g0;
        }
    }
    return true;
}

bool penumbraAaDepthTexel(PenumbraAaDepthTriangle t, int x, int y, out double d, out double c) {
    const double margin = 1.0lf / 1024.0lf;
    d = 0.0lf;
    c = 0.0lf;
    double x0 = double(x), y0 = double(y), x1 = double(x) + 1.0lf, y1 = double(y) + 1.0lf;
    precise double xl = x0 + margin;
    precise double xh = x1 - margin;
    precise double yl = y0 + margin;
    precise double yh = y1 - margin;
    if (!(t.hi.x > xl && t.lo.x < xh && t.hi.y > yl && t.lo.y < yh)) return false;
    for (int j = 0; j < t.count; ++j) {
        dvec3 a = t.s[j], b = t.s[(j + 1) % t.count];
        precise double nx = b.y - a.y;
        precise double ny = a.x - b.x;
        double poly_lo = 1e300lf, poly_hi = -1e300lf;
        for (int k = 0; k < t.count; ++k) {
            precise double v = nx * t.s[k].x + ny * t.s[k].y;
            poly_lo = min(poly_lo, v);
            poly_hi = max(poly_hi, v);
        }
        precise double bx0 = nx * x0;
        precise double bx1 = nx * x1;
        precise double by0 = ny * y0;
        precise double by1 = ny * y1;
        precise double box_lo = min(bx0, bx1) + min(by0, by1);
        precise double box_hi = max(bx0, bx1) + max(by0, by1);
        precise double slack = margin * (abs(nx) + abs(ny));
        precise double lo_bound = box_lo + slack;
        precise double hi_bound = box_hi - slack;
        if (!(poly_hi > lo_bound && poly_lo < hi_bound)) return false;
    }
    precise double ax0 = t.ga * x0;
    precise double ax1 = t.ga * x1;
    precise double ay0 = t.gb * y0;
    precise double ay1 = t.gb * y1;
    precise double corner = (t.g0 + min(ax0, ax1)) + min(ay0, ay1);
    double dd = max(corner, t.dmin);
    precise double dm = dd - 1e-6lf * ((abs(dd) + abs(t.ga)) + abs(t.gb));
    d = dm;
    c = double(uintBitsToFloat(0x7f800000u));  // +inf: no cover
    for (int k = 0; k < 4; ++k) {
        double cx = (k & 1) != 0 ? x1 : x0, cy = (k >> 1) != 0 ? y1 : y0;
        for (int j = 0; j < t.count; ++j) {
            dvec3 a = t.s[j], b = t.s[(j + 1) % t.count];
            precise double e = (b.x - a.x) * (cy - a.y) - (b.y - a.y) * (cx - a.x);
            precise double scale = ((abs(b.x - a.x) + abs(b.y - a.y)) + abs(cx - a.x)) + abs(cy - a.y);
            precise double lhs = e * t.orientation;
            precise double rhs = (1e-9lf * scale) * scale;
            if (!(lhs > rhs)) return true;
        }
    }
    precise double far_corner = (t.g0 + max(ax0, ax1)) + max(ay0, ay1);
    double cc = min(far_corner, t.dmax);
    precise double cm = cc + 1e-6lf * ((abs(cc) + abs(t.ga)) + abs(t.gb));
    c = cm;
    return true;
}

#endif
