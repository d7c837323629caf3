// Bevy's deferred G-buffer normal (bevy_pbr deferred_gbuffer_from_pbr_input): .a holds the
// octahedral normal in its low 24 bits (12 bits per axis) and 8 flag bits. Returns the unit
// normal in xyz and w = 1, or zero where nothing was drawn (all words 0). Shared by the
// volumes' blur and the image-space passes.
fn gbuffer_decode_normal(g: vec4<u32>) -> vec4<f32> {
    if all(g == vec4<u32>(0u)) {
        return vec4(0.0);
    }
    let a = g.a & 0xFFFFFFu;
    let v = vec2(f32(a & 0xFFFu), f32((a >> 12u) & 0xFFFu)) / 4095.0 * 2.0 - 1.0;
    var n = vec3(v, 1.0 - abs(v.x) - abs(v.y));
    let t = clamp(-n.z, 0.0, 1.0);
    n = vec3(n.xy + select(vec2(t), vec2(-t), n.xy >= vec2(0.0)), n.z);
    return vec4(normalize(n), 1.0);
}
