use super::text::{self, Document, MAX_NESTING, ValueKind};
use super::*;
use gdshader::diag::{SourceDb, render_human};

fn parse(source: &str) -> Document {
    let mut db = SourceDb::new();
    let file = db.add("t.tres", source.to_string(), None);
    match text::parse(source, file) {
        Ok(doc) => doc,
        Err(d) => panic!("{}", render_human(&db, &[d], false)),
    }
}

/// The rendered error of a malformed file.
fn error_of(source: &str) -> String {
    let mut db = SourceDb::new();
    let file = db.add("bad.tres", source.to_string(), None);
    match text::parse(source, file) {
        Ok(_) => panic!("parsed: {source}"),
        Err(d) => render_human(&db, &[d], false),
    }
}

/// The value of the first property under `[resource]` in `text`.
fn value(text: &str) -> Value {
    let doc = parse(&format!("[gd_resource type=\"Resource\" format=3]\n\n[resource]\nv = {text}\n"));
    doc.sections[1].properties[0].value.clone()
}

#[test]
fn headers_and_properties_keep_names_values_and_spans() {
    let source = "[gd_resource type=\"ShaderMaterial\" load_steps=3 format=3 uid=\"uid://b7x\"]\n\n\
                  [ext_resource type=\"Shader\" uid=\"uid://c1\" path=\"res://sky.gdshader\" id=\"1_abc\"]\n\n\
                  [resource]\nshader = ExtResource(\"1_abc\")\nshader_parameter/sun_color = Color(1, 0.5, 0.25, 1)\n";
    let doc = parse(source);
    assert_eq!(doc.sections.len(), 3);
    let header = &doc.sections[0];
    assert_eq!(header.tag, "gd_resource");
    assert_eq!(header.attribute_str("type"), Some("ShaderMaterial"));
    assert_eq!(header.attribute("load_steps").map(|a| a.value.kind.clone()), Some(ValueKind::Int(3)));
    assert_eq!(&source[header.span.clone()], &source[..source.find('\n').unwrap()]);
    let ext = &doc.sections[1];
    assert_eq!(ext.attribute_str("path"), Some("res://sky.gdshader"));
    let resource = &doc.sections[2];
    assert_eq!(resource.property("shader").map(|p| p.value.kind.clone()), Some(ValueKind::ExtResource("1_abc".into())));
    let color = resource.property("shader_parameter/sun_color").unwrap();
    assert_eq!(&source[color.name_span.clone()], "shader_parameter/sun_color");
    assert_eq!(&source[color.value.span.clone()], "Color(1, 0.5, 0.25, 1)");
    let ValueKind::Constructor { name, args } = &color.value.kind else { panic!() };
    assert_eq!(name, "Color");
    assert_eq!(args.iter().map(|a| a.number().unwrap()).collect::<Vec<_>>(), vec![1.0, 0.5, 0.25, 1.0]);
    assert_eq!(&source[args[1].span.clone()], "0.5");
}

#[test]
fn scenes_nodes_and_connections_parse() {
    let doc = parse(
        "[gd_scene load_steps=2 format=3 uid=\"uid://x\"]\n\n[sub_resource type=\"Environment\" id=\"Environment_1\"]\n\
         background_mode = 2\n\n[node name=\"Root\" type=\"Node3D\"]\n\n\
         [node name=\"WorldEnvironment\" type=\"WorldEnvironment\" parent=\".\"]\nenvironment = SubResource(\"Environment_1\")\n\n\
         [connection signal=\"ready\" from=\".\" to=\".\" method=\"_on_ready\" flags=3]\n",
    );
    let tags: Vec<&str> = doc.sections.iter().map(|s| s.tag.as_str()).collect();
    assert_eq!(tags, ["gd_scene", "sub_resource", "node", "node", "connection"]);
    assert_eq!(doc.sections[3].attribute_str("parent"), Some("."));
    assert_eq!(doc.sections[4].attribute("flags").map(|a| a.value.kind.clone()), Some(ValueKind::Int(3)));
}

#[test]
fn numbers_ints_floats_exponents_and_infinities() {
    assert_eq!(value("42").kind, ValueKind::Int(42));
    assert_eq!(value("-7").kind, ValueKind::Int(-7));
    assert_eq!(value("9223372036854775807").kind, ValueKind::Int(i64::MAX));
    assert_eq!(value("0.5").kind, ValueKind::Float(0.5));
    assert_eq!(value("-.25").kind, ValueKind::Float(-0.25));
    assert_eq!(value("1e-05").kind, ValueKind::Float(1e-5));
    assert_eq!(value("2.5E+3").kind, ValueKind::Float(2500.0));
    assert_eq!(value("3.").kind, ValueKind::Float(3.0));
    assert_eq!(value("inf").kind, ValueKind::Float(f64::INFINITY));
    assert_eq!(value("-inf").kind, ValueKind::Float(f64::NEG_INFINITY));
    assert_eq!(value("inf_neg").kind, ValueKind::Float(f64::NEG_INFINITY));
    assert!(matches!(value("nan").kind, ValueKind::Float(f) if f.is_nan()));
    // Beyond f64: infinity, as Godot's own reader gives.
    assert_eq!(value("1e400").kind, ValueKind::Float(f64::INFINITY));
}

#[test]
fn strings_unescape_and_span_many_lines() {
    assert_eq!(value(r#""a \"b\" \\ c\nd\te""#).kind, ValueKind::String("a \"b\" \\ c\nd\te".into()));
    assert_eq!(value(r#""\u00e9\u4e2d\uD83D\uDE00\U01F600""#).kind, ValueKind::String("é中😀😀".into()));
    assert_eq!(value(r#""\b\f\r\'""#).kind, ValueKind::String("\u{8}\u{c}\r'".into()));
    let code = "\"shader_type sky;\n\nvoid sky() {\n\tCOLOR = vec3(0.5); // \\\"quoted\\\"\n}\n\"";
    let v = value(code);
    assert_eq!(
        v.kind,
        ValueKind::String("shader_type sky;\n\nvoid sky() {\n\tCOLOR = vec3(0.5); // \"quoted\"\n}\n".into())
    );
    assert_eq!(v.span.len(), code.len());
    assert_eq!(value("&\"sky\"").kind, ValueKind::StringName("sky".into()));
    assert_eq!(value("^\"../Sun\"").kind, ValueKind::NodePath("../Sun".into()));
    assert_eq!(value("StringName(\"a\")").kind, ValueKind::StringName("a".into()));
    assert_eq!(value("NodePath(\"Sun:rotation\")").kind, ValueKind::NodePath("Sun:rotation".into()));
    // A `;` inside a string is text, not a comment.
    assert_eq!(value("\"a;b\" ; a comment").kind, ValueKind::String("a;b".into()));
}

#[test]
fn keywords_arrays_and_dictionaries() {
    assert_eq!(value("true").kind, ValueKind::Bool(true));
    assert_eq!(value("false").kind, ValueKind::Bool(false));
    assert_eq!(value("null").kind, ValueKind::Null);
    let ValueKind::Array(items) = value("[1, \"two\", [3.0], ]").kind else { panic!() };
    assert_eq!(items.len(), 3);
    assert_eq!(items[0].kind, ValueKind::Int(1));
    let ValueKind::TypedArray { element, items } = value("Array[int]([1, 2])").kind else { panic!() };
    assert_eq!((element.as_str(), items.len()), ("int", 2));
    let ValueKind::TypedArray { element, .. } = value("Array[ExtResource(\"1_s\")]([])").kind else { panic!() };
    assert_eq!(element, "ExtResource(\"1_s\")");
    let ValueKind::Dictionary(entries) = value("{\n\"k\": Vector2(1, 2),\n3: [null]\n}").kind else { panic!() };
    assert_eq!(entries.len(), 2);
    assert_eq!(entries[0].0.kind, ValueKind::String("k".into()));
    let ValueKind::TypedDictionary { key, value: v, entries } = value("Dictionary[String, int]({\n\"a\": 1\n})").kind
    else {
        panic!()
    };
    assert_eq!((key.as_str(), v.as_str(), entries.len()), ("String", "int", 1));
    assert_eq!(value("{}").kind, ValueKind::Dictionary(Vec::new()));
}

#[test]
fn constructors_of_every_builtin_type() {
    for (text, n) in [
        ("Vector2(1, 2)", 2),
        ("Vector2i(1, 2)", 2),
        ("Vector3(0, 1, 0)", 3),
        ("Vector3i(0, 1, 0)", 3),
        ("Vector4(1, 2, 3, 4)", 4),
        ("Vector4i(1, 2, 3, 4)", 4),
        ("Color(1, 1, 1, 1)", 4),
        ("Quaternion(0, 0, 0, 1)", 4),
        ("Plane(0, 1, 0, 2)", 4),
        ("Rect2(0, 0, 1, 1)", 4),
        ("Rect2i(0, 0, 1, 1)", 4),
        ("AABB(0, 0, 0, 1, 1, 1)", 6),
        ("Transform2D(1, 0, 0, 1, 0, 0)", 6),
        ("Basis(1, 0, 0, 0, 1, 0, 0, 0, 1)", 9),
        ("Transform3D(1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0)", 12),
        ("Projection(1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1)", 16),
        ("PackedFloat32Array(0.1, 0.5, inf)", 3),
        ("PackedFloat64Array()", 0),
        ("PackedInt32Array(1, -2)", 2),
        ("PackedInt64Array(9007199254740993)", 1),
        ("PackedByteArray(0, 255)", 2),
        ("PackedByteArray(\"AAEC\")", 1),
        ("PackedStringArray(\"a\", \"b\")", 2),
        ("PackedVector2Array(0, 0, 1, 1)", 4),
        ("PackedVector3Array(0, 0, 0)", 3),
        ("PackedColorArray(0, 0, 0, 1, 1, 1, 1, 1)", 8),
        ("PackedVector4Array(1, 2, 3, 4)", 4),
    ] {
        let v = value(text);
        let ValueKind::Constructor { args, .. } = &v.kind else { panic!("{text}: {v:?}") };
        assert_eq!(args.len(), n, "{text}");
    }
    assert_eq!(value("SubResource(\"Noise_1\")").kind, ValueKind::SubResource("Noise_1".into()));
    assert_eq!(value("ExtResource( 2 )").kind, ValueKind::ExtResource("2".into()));
    assert_eq!(value("Resource(\"res://a.tres\")").kind, ValueKind::Resource("res://a.tres".into()));
    let ValueKind::Object { class, properties } =
        value("Object(InputEventKey,\"resource_local_to_scene\":false,\"keycode\":65)").kind
    else {
        panic!()
    };
    assert_eq!((class.as_str(), properties.len()), ("InputEventKey", 2));
    assert_eq!(properties[1], ("keycode".to_string(), properties[1].1.clone()));
}

#[test]
fn comments_quoted_keys_and_format_2() {
    let doc = parse(
        "; a comment\n[gd_resource type=\"ShaderMaterial\" load_steps=2 format=2]\n\n[ext_resource path=\"res://s.shader\" type=\"Shader\" id=1]\n\n[resource]\n\
         shader = ExtResource( 1 ) ; trailing\nshader_param/c = Color( 1, 0, 0, 1 )\n\"metadata/a b\" = 1\n",
    );
    let resource = &doc.sections[2];
    assert_eq!(resource.properties.len(), 3);
    assert_eq!(resource.properties[2].name, "metadata/a b");
    assert_eq!(doc.sections[1].attribute("id").and_then(|a| a.value.id()), Some("1".into()));
}

#[test]
fn malformed_files_are_located_errors() {
    let cases = [
        ("missing_bracket", "[gd_resource type=\"ShaderMaterial\" format=3\n\n[resource]\n"),
        ("missing_value", "[gd_resource type=\"ShaderMaterial\" format=3]\n\n[resource]\nshader = \n"),
        (
            "unterminated_string",
            "[gd_resource type=\"Shader\" format=3]\n\n[resource]\ncode = \"shader_type sky;\nvoid sky() {}\n",
        ),
        ("bad_escape", "[gd_resource type=\"Shader\" format=3]\n\n[resource]\ncode = \"a \\q b\"\n"),
        (
            "unknown_constructor",
            "[gd_resource type=\"ShaderMaterial\" format=3]\n\n[resource]\nshader_parameter/c = Colour(1, 1, 1, 1)\n",
        ),
        (
            "wrong_arity",
            "[gd_resource type=\"ShaderMaterial\" format=3]\n\n[resource]\nshader_parameter/v = Vector3(1, 2)\n",
        ),
        (
            "int_too_large",
            "[gd_resource type=\"ShaderMaterial\" format=3]\n\n[resource]\nshader_parameter/n = 99999999999999999999\n",
        ),
        (
            "unclosed_array",
            "[gd_resource type=\"ShaderMaterial\" format=3]\n\n[resource]\nshader_parameter/a = [1, 2\nshader_parameter/b = 3\n",
        ),
        ("lone_surrogate", "[gd_resource type=\"Shader\" format=3]\n\n[resource]\ncode = \"\\uD83D!\"\n"),
    ];
    for (name, source) in cases {
        insta::assert_snapshot!(name, error_of(source));
    }
}

#[test]
fn deep_nesting_is_refused_before_pest_recurses() {
    let ok = format!("{}{}", "[".repeat(MAX_NESTING - 1), "]".repeat(MAX_NESTING - 1));
    assert!(matches!(value(&ok).kind, ValueKind::Array(_)));
    let deep = format!("[gd_resource format=3]\n[resource]\nv = {}\n", "[".repeat(100_000));
    let err = error_of(&deep);
    assert!(err.contains("E802") && err.contains("bad.tres:3:"), "{err}");
}

/// A sample holding every construct, for the no-panic tests.
const SAMPLE: &str = "[gd_resource type=\"ShaderMaterial\" load_steps=4 format=3 uid=\"uid://b\"]\n\n\
    [ext_resource type=\"Texture2D\" path=\"res://t.png\" id=\"1\"]\n\n\
    [sub_resource type=\"Shader\" id=\"Shader_a\"]\ncode = \"shader_type sky;\n// \\\"q\\\" \\u00e9\nvoid sky() { COLOR = vec3(1.0); }\n\"\n\n\
    [sub_resource type=\"FastNoiseLite\" id=\"N\"]\nfrequency = 0.02\noffset = Vector3(1, -2.5e3, inf)\n\n\
    [resource]\nshader = SubResource(\"Shader_a\")\nshader_parameter/a = [1, { \"k\": Array[int]([2]) }, &\"s\", ^\"p\", null]\n\
    shader_parameter/b = PackedVector3Array(0, 1, 2)\nshader_parameter/c = Object(Foo, \"x\": Transform3D(1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0))\n\
    shader_parameter/t = ExtResource(\"1\") ; done\n";

fn parse_any(bytes: &[u8]) {
    let text = String::from_utf8_lossy(bytes);
    let mut db = SourceDb::new();
    let file = db.add("m.tres", text.to_string(), None);
    if let Err(d) = text::parse(&text, file) {
        // Rendering must not panic either (spans stay inside the text).
        let _ = render_human(&db, &[d], false);
    }
}

#[test]
fn no_truncation_of_the_sample_panics() {
    assert!(text::parse(SAMPLE, SourceDb::new().add("s", SAMPLE.into(), None)).is_ok());
    let bytes = SAMPLE.as_bytes();
    for end in 0..=bytes.len() {
        parse_any(&bytes[..end]);
    }
}

#[test]
fn no_byte_mutation_of_the_sample_panics() {
    let bytes = SAMPLE.as_bytes();
    let replacements =
        [b'"', b'\\', b'[', b']', b'(', b')', b'{', b'}', b',', b'=', b';', b'\n', b'-', b'9', b'e', 0, 0xFF];
    // Every position with a few replacements, and deletions: a deterministic sweep.
    for i in 0..bytes.len() {
        let r = replacements[i % replacements.len()];
        let mut mutated = bytes.to_vec();
        mutated[i] = r;
        parse_any(&mutated);
        let mut deleted = bytes.to_vec();
        deleted.remove(i);
        parse_any(&deleted);
    }
}

/// A throwaway Godot project under the target directory.
fn project(name: &str, files: &[(&str, &[u8])]) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("gdsky_godot_unit_{}", std::process::id())).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("project.godot"), "config_version=5\n").unwrap();
    for (path, contents) in files {
        let p = dir.join(path);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, contents).unwrap();
    }
    dir
}

const SKY: &[u8] = b"shader_type sky;\nuniform vec3 tint : source_color = vec3(1.0);\nuniform float gain = 1.0;\nuniform int steps = 4;\n\
uniform bool on = false;\nuniform bvec3 mask;\nuniform sampler2D clouds;\nuniform float flag = 0.0;\n\
void sky() { COLOR = tint * gain * flag * float(steps) * texture(clouds, SKY_COORDS).r; }\n";

#[test]
fn a_material_by_path_gives_its_shader_values_and_textures() {
    let dir = project(
        "by_path",
        &[
            ("shaders/sky.gdshader", SKY),
            ("tex/clouds.png", b"not read here"),
            (
                "materials/sky.tres",
                b"[gd_resource type=\"ShaderMaterial\" load_steps=3 format=3]\n\n\
                  [ext_resource type=\"Shader\" path=\"res://shaders/sky.gdshader\" id=\"1_a\"]\n\
                  [ext_resource type=\"Texture2D\" path=\"../tex/clouds.png\" id=\"2_b\"]\n\n\
                  [resource]\nshader = ExtResource(\"1_a\")\nshader_parameter/tint = Color(1, 0.5, 0.25, 1)\n\
                  shader_parameter/gain = 2\nshader_parameter/steps = 8\nshader_parameter/on = true\nshader_parameter/mask = 5\n\
                  shader_parameter/clouds = ExtResource(\"2_b\")\nshader_parameter/removed = 1.0\nshader_parameter/flag = true\n",
            ),
        ],
    );
    let material = load_sky_material(&dir.join("materials/sky.tres")).unwrap();
    let canonical = std::fs::canonicalize(&dir).unwrap();
    assert_eq!(material.shader, MaterialShader::File(canonical.join("shaders/sky.gdshader")));
    let front = material.check_shader().unwrap();
    let settings = material.settings(front.shader.as_ref().unwrap()).unwrap();
    let pairs: Vec<(&str, &str)> = settings.uniforms.iter().map(|u| (u.name.as_str(), u.text.as_str())).collect();
    assert_eq!(
        pairs,
        [
            ("tint", "1.0,0.5,0.25"),
            ("gain", "2.0"),
            ("steps", "8"),
            ("on", "true"),
            ("mask", "true,false,true"),
            // A bool for a float uniform: Godot's conversion, as Godot writes such files.
            ("flag", "1.0")
        ]
    );
    assert_eq!(settings.textures.len(), 1);
    assert_eq!(settings.textures[0].path, dir.join("materials/../tex/clouds.png"));
    assert!(settings.warnings.contains("W800") && settings.warnings.contains("`removed`"), "{}", settings.warnings);
}

#[test]
fn a_scene_leads_through_environment_and_sky_to_an_embedded_shader() {
    let dir = project(
        "scene",
        &[(
            "world.tscn",
            b"[gd_scene load_steps=5 format=3]\n\n[sub_resource type=\"Shader\" id=\"Shader_k\"]\n\
              code = \"shader_type sky;\nuniform float gain = 1.0;\nvoid sky() { COLOR = vec3(gain); }\n\"\n\n\
              [sub_resource type=\"ShaderMaterial\" id=\"M\"]\nshader = SubResource(\"Shader_k\")\nshader_parameter/gain = 0.5\n\n\
              [sub_resource type=\"Sky\" id=\"S\"]\nsky_material = SubResource(\"M\")\n\n\
              [sub_resource type=\"Environment\" id=\"E\"]\nbackground_mode = 2\nsky = SubResource(\"S\")\n\n\
              [node name=\"Main\" type=\"Node3D\"]\n\n[node name=\"WorldEnvironment\" type=\"WorldEnvironment\" parent=\".\"]\n\
              environment = SubResource(\"E\")\n",
        )],
    );
    let material = load_sky_material(&dir.join("world.tscn")).unwrap();
    let MaterialShader::Embedded { name, code } = &material.shader else { panic!("{:?}", material.shader) };
    assert_eq!(name, "world.tscn::Shader_k");
    assert!(code.starts_with("shader_type sky;\n"));
    let front = material.check_shader().unwrap();
    let settings = material.settings(front.shader.as_ref().unwrap()).unwrap();
    assert_eq!(settings.uniforms[0].text, "0.5");
}

#[test]
fn material_errors_are_located_in_the_file_that_holds_them() {
    let dir = project(
        "errors",
        &[
            ("sky.gdshader", SKY),
            ("procedural.tres", b"[gd_resource type=\"ProceduralSkyMaterial\" format=3]\n\n[resource]\nsky_top_color = Color(0, 0, 1, 1)\n"),
            ("no_env.tscn", b"[gd_scene format=3]\n\n[node name=\"Main\" type=\"Node3D\"]\n"),
            (
                "jpg.tres",
                b"[gd_resource type=\"ShaderMaterial\" format=3]\n\n[ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1\"]\n\
                  [ext_resource type=\"Texture2D\" path=\"res://clouds.jpg\" id=\"2\"]\n\n[resource]\nshader = ExtResource(\"1\")\n\
                  shader_parameter/clouds = ExtResource(\"2\")\n",
            ),
            (
                "image_texture.tres",
                b"[gd_resource type=\"ShaderMaterial\" format=3]\n\n[ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1\"]\n\
                  [sub_resource type=\"ImageTexture\" id=\"G\"]\n\n[resource]\nshader = ExtResource(\"1\")\n\
                  shader_parameter/clouds = SubResource(\"G\")\n",
            ),
            (
                "missing_id.tres",
                b"[gd_resource type=\"ShaderMaterial\" format=3]\n\n[resource]\nshader = ExtResource(\"9_x\")\n",
            ),
            (
                "wrong_type.tres",
                b"[gd_resource type=\"ShaderMaterial\" format=3]\n\n[ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1\"]\n\n\
                  [resource]\nshader = ExtResource(\"1\")\nshader_parameter/tint = Vector2(1, 2)\nshader_parameter/steps = 1.5\n",
            ),
            ("not_utf8.tres", b"[gd_resource format=3]\n[resource]\nv = \"\xff\"\n"),
            ("format4.tres", b"[gd_resource type=\"ShaderMaterial\" format=4]\n"),
        ],
    );
    let load = |name: &str| load_sky_material(&dir.join(name)).map(|_| ()).unwrap_err().to_string();
    let strip = |s: String| s.replace(&format!("{}/", dir.display()), "");
    for name in [
        "procedural.tres",
        "no_env.tscn",
        "jpg.tres",
        "image_texture.tres",
        "missing_id.tres",
        "not_utf8.tres",
        "format4.tres",
    ] {
        insta::assert_snapshot!(format!("material_{name}"), strip(load(name)));
    }
    let material = load_sky_material(&dir.join("wrong_type.tres")).unwrap();
    let front = material.check_shader().unwrap();
    let err = material.settings(front.shader.as_ref().unwrap()).unwrap_err();
    insta::assert_snapshot!("material_wrong_type.tres", strip(err));
    // A file that is not there: unreadable (exit 2), not malformed.
    assert!(matches!(load_sky_material(&dir.join("absent.tres")), Err(MaterialError::Read(_))));
}

#[test]
fn gradient_and_curve_textures_are_read_with_their_resources() {
    let dir = project(
        "ramps",
        &[
            (
                "sky.gdshader",
                b"shader_type sky;\nuniform sampler2D clouds;\nuniform sampler2D bands;\n\
                  void sky() { COLOR = texture(clouds, SKY_COORDS).rgb * texture(bands, SKY_COORDS).r; }\n",
            ),
            (
                "ramps.tres",
                b"[gd_resource type=\"ShaderMaterial\" format=3]\n\n[ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1\"]\n\n\
                  [sub_resource type=\"Gradient\" id=\"moon\"]\noffsets = PackedFloat32Array(0, 0.6)\n\
                  colors = PackedColorArray(1, 1, 0.9, 1, 0, 0, 0, 0)\n\n\
                  [sub_resource type=\"GradientTexture2D\" id=\"disc\"]\ngradient = SubResource(\"moon\")\nwidth = 32\n\
                  use_hdr = true\nfill = 1\nfill_from = Vector2(0.5, 0.5)\nfill_to = Vector2(1, 0.5)\nrepeat = 2\n\n\
                  [sub_resource type=\"Curve\" id=\"c\"]\n_limits = [-1.0, 2.0, 0.0, 1.0]\nbake_resolution = 64\n\
                  _data = [Vector2(0, 1), 0.0, -1.5, 0, 0, Vector2(1, 0), 0.25, 0.0, 0, 1]\npoint_count = 2\n\n\
                  [sub_resource type=\"CurveTexture\" id=\"ct\"]\ncurve = SubResource(\"c\")\ntexture_mode = 1\n\n\
                  [resource]\nshader = ExtResource(\"1\")\nshader_parameter/clouds = SubResource(\"disc\")\n\
                  shader_parameter/bands = SubResource(\"ct\")\n",
            ),
            (
                "bad_curve.tres",
                b"[gd_resource type=\"ShaderMaterial\" format=3]\n\n[ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1\"]\n\n\
                  [sub_resource type=\"Curve\" id=\"c\"]\n_data = [Vector2(0, 1), 0.0, 0.0, 0, 7]\n\n\
                  [sub_resource type=\"CurveTexture\" id=\"ct\"]\ncurve = SubResource(\"c\")\n\n\
                  [resource]\nshader = ExtResource(\"1\")\nshader_parameter/clouds = SubResource(\"ct\")\n",
            ),
        ],
    );
    let material = load_sky_material(&dir.join("ramps.tres")).unwrap();
    let front = material.check_shader().unwrap();
    let shader = front.shader.as_ref().unwrap();
    let settings = material.settings(shader).unwrap();
    let ramps = &settings.generated_ramps;
    assert_eq!(ramps.len(), 2, "{ramps:?}");
    let crate::generated::RampTexture::Gradient2D(disc) = &ramps[0].texture else { panic!("{:?}", ramps[0]) };
    assert_eq!((disc.width, disc.height, disc.use_hdr, disc.fill, disc.repeat), (32, 64, true, 1, 2));
    assert_eq!((disc.fill_from, disc.fill_to), ([0.5, 0.5], [1.0, 0.5]));
    assert_eq!(disc.gradient.as_ref().unwrap().offsets, [0.0, 0.6]);
    let crate::generated::RampTexture::Curve(ct) = &ramps[1].texture else { panic!("{:?}", ramps[1]) };
    assert_eq!(ct.texture_mode, 1);
    let curve = ct.curve.as_ref().unwrap();
    assert_eq!((curve.min_value, curve.max_value, curve.bake_resolution), (-1.0, 2.0, 64));
    assert_eq!(
        (curve.points[0].right_tangent, curve.points[1].left_tangent, curve.points[1].right_mode),
        (-1.5, 0.25, 1)
    );
    assert_eq!(ramps[0].texture.image().unwrap().format, crate::generated::RampFormat::Rgbaf);
    assert!(ramps.iter().all(|r| r.texture.generate().is_ok()));
    // A tangent mode Godot does not have: located at the value.
    let bad = load_sky_material(&dir.join("bad_curve.tres")).unwrap();
    let err = bad.settings(bad.check_shader().unwrap().shader.as_ref().unwrap()).unwrap_err();
    assert!(err.contains("E815") && err.contains("a tangent mode, 0 (free) or 1 (linear), not"), "{err}");
    assert!(err.contains("bad_curve.tres:6:38"), "{err}");
}

fn fixture(path: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fixtures/godot_project").join(path)
}

#[test]
fn an_environment_leads_through_an_ext_resource_material_to_its_noise_texture() {
    let material = load_sky_material(&fixture("environments/sky_environment.tres")).unwrap();
    let root = std::fs::canonicalize(fixture("")).unwrap();
    assert_eq!(material.shader, MaterialShader::File(root.join("shaders/test_sky.gdshader")));
    // The parameters are located in the material's own file, not the environment's.
    assert!(material.db.name(material.file).ends_with("materials/sky_material.tres"));
    let front = material.check_shader().unwrap();
    let settings = material.settings(front.shader.as_ref().unwrap()).unwrap();
    assert_eq!(settings.uniforms.len(), 6);
    assert_eq!(settings.textures[0].path, root.join("textures/bands.png"));
    let clouds = &settings.generated[0];
    assert_eq!(clouds.name, "clouds");
    let t = &clouds.texture;
    assert_eq!((t.width, t.height, t.seamless, t.normalize), (64, 32, true, true));
    let noise = t.noise.as_ref().unwrap();
    assert_eq!((noise.noise_type, noise.seed, noise.frequency, noise.fractal_octaves), (3, 7, 0.05, 3));
    assert_eq!(noise.fractal_gain, 0.5, "an unset property keeps Godot's default");
    assert!(settings.warnings.is_empty(), "{}", settings.warnings);
}

#[test]
fn a_noise_property_of_the_wrong_kind_is_located() {
    let dir = project(
        "noise",
        &[
            ("sky.gdshader", SKY),
            (
                "m.tres",
                b"[gd_resource type=\"ShaderMaterial\" format=3]\n\n[ext_resource type=\"Shader\" path=\"res://sky.gdshader\" id=\"1\"]\n\n\
                  [sub_resource type=\"FastNoiseLite\" id=\"N\"]\nfrequency = \"high\"\n\n\
                  [sub_resource type=\"Gradient\" id=\"G\"]\noffsets = PackedFloat32Array(0, 0.5, 1)\ncolors = PackedColorArray(0, 0, 0, 1, 1, 1, 1, 1)\n\n\
                  [sub_resource type=\"NoiseTexture2D\" id=\"T\"]\nwidth = 8.5\nnoise = SubResource(\"N\")\n\n\
                  [resource]\nshader = ExtResource(\"1\")\nshader_parameter/clouds = SubResource(\"T\")\n",
            ),
        ],
    );
    let material = load_sky_material(&dir.join("m.tres")).unwrap();
    let front = material.check_shader().unwrap();
    let err = material.settings(front.shader.as_ref().unwrap()).unwrap_err();
    assert!(err.contains("error[E815]: `width` must be an int, not a float") && err.contains("m.tres:13:9"), "{err}");
    let mismatched = std::fs::read_to_string(dir.join("m.tres"))
        .unwrap()
        .replace("width = 8.5\n", "color_ramp = SubResource(\"G\")\n")
        .replace("frequency = \"high\"", "frequency = 0.1");
    std::fs::write(dir.join("m.tres"), mismatched).unwrap();
    let material = load_sky_material(&dir.join("m.tres")).unwrap();
    let err = material.settings(front.shader.as_ref().unwrap()).unwrap_err();
    assert!(err.contains("the gradient has 3 offsets and 2 colors"), "{err}");
}

#[test]
fn binary_resources_are_refused_by_name() {
    let dir = project(
        "binary",
        &[(
            "env.tres",
            b"[gd_resource type=\"Environment\" format=3]\n\n[ext_resource type=\"Sky\" path=\"res://sky.res\" id=\"1\"]\n\n\
              [resource]\nsky = ExtResource(\"1\")\n",
        )],
    );
    let err = load_sky_material(&dir.join("env.tres")).unwrap_err().to_string();
    assert!(err.contains("error[E811]") && err.contains("env.tres:6:7") && err.contains("not binary ones"), "{err}");
}

#[test]
fn no_truncation_of_a_material_panics_the_loader() {
    let material = std::fs::read(fixture("materials/sky_material.tres")).unwrap();
    let dir = project(
        "truncated",
        &[
            ("shaders/test_sky.gdshader", &std::fs::read(fixture("shaders/test_sky.gdshader")).unwrap()),
            ("textures/bands.png", &std::fs::read(fixture("textures/bands.png")).unwrap()),
        ],
    );
    let path = dir.join("m.tres");
    let mut loaded = 0;
    for end in 0..=material.len() {
        std::fs::write(&path, &material[..end]).unwrap();
        if let Ok(m) = load_sky_material(&path) {
            loaded += 1;
            if let Ok(front) = m.check_shader()
                && let Some(shader) = front.shader.as_ref()
            {
                let _ = m.settings(shader);
            }
        }
    }
    // Only the prefixes that end after the last property's value (or within the trailing
    // newline) still name a shader.
    assert!(loaded > 0 && loaded < material.len() / 2, "{loaded}");
    // A folder named like a material is not read (regular files only): unreadable, exit 2.
    std::fs::create_dir_all(dir.join("folder.tres")).unwrap();
    assert!(matches!(load_sky_material(&dir.join("folder.tres")), Err(MaterialError::Read(_))));
}

/// A resource path that leaves the project (`res://../…`, `../../…`, an absolute path) is an
/// error naming it, and the file is not read: nothing of it reaches a message (issue #22).
#[test]
fn resource_paths_are_confined_to_the_project() {
    for (i, written) in
        ["res://../../../../../etc/passwd", "../../../../../etc/passwd", "/etc/passwd"].iter().enumerate()
    {
        let tres = format!(
            "[gd_resource type=\"ShaderMaterial\" load_steps=2 format=3]\n\n[ext_resource type=\"Shader\" path=\"{written}\" id=\"1\"]\n\n[resource]\nshader = ExtResource(\"1\")\n"
        );
        let dir = project(&format!("confined_{i}"), &[("materials/sky.tres", tres.as_bytes())]);
        let message = match crate::load_sky_material(&dir.join("materials/sky.tres")) {
            Err(crate::MaterialError::Invalid(m)) => m,
            Err(crate::MaterialError::Read(m)) => panic!("{written}: read, not refused: {m}"),
            Ok(_) => panic!("{written}: loaded"),
        };
        assert!(message.contains("outside the project"), "{written}: {message}");
        assert!(!message.contains("root:"), "{written}: nothing of /etc/passwd is shown: {message}");
    }
}
