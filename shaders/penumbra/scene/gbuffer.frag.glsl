// penumbra scene helper — G-buffer fragment stage. Writes
//   location 0: world position (xyz) and 1 (w marks covered pixels; the clear value has w = 0),
//   location 1: the triangle's geometric normal (xyz, unit, from the face-normal SSBO, so the
//               light-facing test of sintorn2008 Fig. 2 sees the triangle itself; outward for
//               closed meshes, towards the camera for open ones) and the triangle id in w (as
//               float bits),
//   location 2: the interpolated shading normal (xyz) for lighting.
// SSBO binding 0 = vec4 face normals by triangle; uniform 1 = first triangle id of this draw.
// World positions are not the interpolated varying: the pixel-centre ray (unprojected with the
// double-precision inverse view-projection, uniform 2, viewport size uniform 3) is intersected
// with the triangle's own plane in double (vertices from SSBO 1 = interleaved position+normal
// floats, SSBO 2 = indices), so each view sample lies on its surface to float rounding (~1 ulp)
// instead of the ~1e-5 relative error perspective interpolation can reach at grazing angles. An
// engine's depth-reconstructed samples are noisier; penumbra's coplanar tolerance must cover them.
layout(location = 0) in vec3 penumbraSceneWorld;
layout(location = 1) in vec3 penumbraSceneNormal;
layout(location = 0) out vec4 penumbraSceneOutPosition;
layout(location = 1) out vec4 penumbraSceneOutFace;
layout(location = 2) out vec4 penumbraSceneOutShading;

layout(std430, binding = 0) readonly buffer PenumbraSceneFaceNormals { vec4 penumbraSceneFaceNormals[]; };
layout(location = 1) uniform uint penumbraSceneFirstTriangle;
layout(location = 2) uniform dmat4 penumbraSceneInverseViewProjection;
layout(location = 3) uniform vec2 penumbraSceneViewport;
layout(std430, binding = 1) readonly buffer PenumbraSceneVertices { float penumbraSceneVertices[]; };
layout(std430, binding = 2) readonly buffer PenumbraSceneIndices { uint penumbraSceneIndices[]; };

dvec3 penumbraSceneVertex(uint corner) {
    uint v = penumbraSceneIndices[corner] * 6u;
    return dvec3(penumbraSceneVertices[v], penumbraSceneVertices[v + 1u], penumbraSceneVertices[v + 2u]);
}

dvec3 penumbraSceneUnproject(dvec2 ndc, double z) {
    dvec4 h = penumbraSceneInverseViewProjection * dvec4(ndc, z, 1.0);
    return h.xyz / h.w;
}

void main() {
    uint triangle = penumbraSceneFirstTriangle + uint(gl_PrimitiveID);
    vec3 face = penumbraSceneFaceNormals[triangle].xyz;
    vec3 shading = normalize(penumbraSceneNormal);
    // Open meshes are seen from both sides: report the side facing the camera. Closed meshes keep
    // their outward normal: a pixel centre just past a silhouette can land on a camera-back-facing
    // triangle, and its true orientation is what the light-facing test (Fig. 2) must see.
    if (!gl_FrontFacing && penumbraSceneFaceNormals[triangle].w == 0.0) {
        face = -face;
        shading = -shading;
    }
    dvec3 a = penumbraSceneVertex(3u * triangle), b = penumbraSceneVertex(3u * triangle + 1u),
          c = penumbraSceneVertex(3u * triangle + 2u);
    dvec2 ndc = dvec2(gl_FragCoord.xy) / dvec2(penumbraSceneViewport) * 2.0 - 1.0;
    dvec3 origin = penumbraSceneUnproject(ndc, -1.0);
    dvec3 direction = penumbraSceneUnproject(ndc, 1.0) - origin;
    dvec3 n = cross(b - a, c - a);
    double denominator = dot(n, direction);
    vec3 world = penumbraSceneWorld;
    if (denominator != 0.0) {
        double t = dot(n, a - origin) / denominator;
        dvec3 q = origin + t * direction;
        // The rasterizer snaps vertices to subpixels, so a pixel centre near an edge can belong to
        // this triangle while its ray meets the neighbour: clamp the barycentrics so the sample
        // stays on the triangle itself (else it may sit inside a closed mesh past a crease).
        dvec3 e0 = b - a, e1 = c - a, e2 = q - a;
        double d00 = dot(e0, e0), d01 = dot(e0, e1), d11 = dot(e1, e1), d20 = dot(e2, e0), d21 = dot(e2, e1);
        double det = d00 * d11 - d01 * d01;
        if (det > 0.0) {
            double v = (d11 * d20 - d01 * d21) / det;
            double w = (d00 * d21 - d01 * d20) / det;
            dvec3 bary = max(dvec3(1.0 - v - w, v, w), dvec3(0.0));
            bary /= bary.x + bary.y + bary.z;
            q = bary.x * a + bary.y * b + bary.z * c;
        }
        world = vec3(q);
    }
    penumbraSceneOutPosition = vec4(world, 1.0);
    penumbraSceneOutFace = vec4(face, uintBitsToFloat(triangle));
    penumbraSceneOutShading = vec4(shading, 0.0);
}
