//! A glTF refused for extensions it requires that Bevy's loader does not read is told by the
//! extensions' names and what to do (issue 29 item 4: the sample models as three.js and others
//! ship them are Draco-compressed or have WebP textures).

use bevy_caustics::headless::unsupported_extensions;

/// The `gltf` crate's text for a Draco-compressed file (IridescentDishWithOlives as three.js
/// ships it), shortened, with a second extension we name but have no remedy for.
#[test]
fn unsupported_required_extensions_are_named_with_a_remedy() {
    let parser = "invalid glTF file: invalid glTF: accessors[0].bufferView: Missing data; \
        accessors[1].bufferView: Missing data; extensionsRequired[0] = \
        \"KHR_draco_mesh_compression\": Unsupported extension; extensionsRequired[1] = \
        \"EXT_unknown\": Unsupported extension";
    let told = unsupported_extensions(parser).unwrap();
    assert!(
        told.starts_with(
            "it requires glTF extensions KHR_draco_mesh_compression, EXT_unknown that"
        ),
        "{told}"
    );
    assert!(told.contains("gltf-transform/cli copy"), "{told}");
    assert!(!told.contains("Missing data"), "{told}");
    let webp = "invalid glTF: textures[0].source: Missing data; extensionsRequired[0] = \
        \"EXT_texture_webp\": Unsupported extension;";
    let told = unsupported_extensions(webp).unwrap();
    assert!(
        told.contains("EXT_texture_webp") && told.contains(" png "),
        "{told}"
    );
    // The whole line for a file that requires one extension and holds nothing it compresses.
    let alone = "invalid glTF file: invalid glTF: extensionsRequired[0] = \
        \"EXT_bevy_caustics_unknown\": Unsupported extension;";
    assert_eq!(
        unsupported_extensions(alone).as_deref(),
        Some(
            "it requires glTF extension EXT_bevy_caustics_unknown that Bevy's glTF loader does not read"
        )
    );
    // Any other reason is left as it is.
    assert_eq!(
        unsupported_extensions("accessors[0].bufferView: Missing data"),
        None
    );
    assert_eq!(unsupported_extensions(""), None);
}
