#import common

// Mesh reference: triangles with interpolated vertex normals into the same G-buffer as
// the splats (weight 1), shaded by the same pass 3. Ground truth for image errors.

struct MeshVertex {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
}

struct MeshVarying {
    @builtin(position) clip: vec4<f32>,
    @location(0) view_pos: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) color: vec4<f32>,
}

@vertex
fn vs_mesh(v: MeshVertex) -> MeshVarying {
    let view_pos = (frame.view * vec4<f32>(v.position + frame.model_offset, 1.0)).xyz;
    var out: MeshVarying;
    out.clip = frame.proj * vec4<f32>(view_pos, 1.0);
    out.view_pos = view_pos;
    out.normal = (frame.view * vec4<f32>(v.normal, 0.0)).xyz;
    out.color = v.color;
    return out;
}

struct MeshAttributes {
    @location(0) color: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) coverage: vec4<f32>,
}

@fragment
fn fs_mesh(in: MeshVarying) -> MeshAttributes {
    var n = normalize(in.normal);
    n = select(n, -n, dot(n, in.view_pos) > 0.0);
    var out: MeshAttributes;
    out.color = vec4<f32>(in.color.rgb, 1.0);
    out.normal = vec4<f32>(n, -in.view_pos.z);
    out.coverage = vec4<f32>(1.0);
    return out;
}
