extends Node
## gdsky oracle job runner. The page (driver.mjs) queues jobs as JSON text in `window.oracle`; this
## script takes one per idle frame, renders the sky shader in a SubViewport (one frame per energy
## bracket) and hands the pixels back as base64 RGBA8. See crates/skyoracle/src/lib.rs.

var bridge # JavaScriptObject for window.oracle; untyped so that its JS methods can be called.
var viewport: SubViewport
var environment: Environment
var sky: Sky
var shader: Shader
var camera: Camera3D
var sun: DirectionalLight3D
var busy := false


func _ready() -> void:
	viewport = SubViewport.new()
	viewport.size = Vector2i(8, 8)
	viewport.render_target_update_mode = SubViewport.UPDATE_ALWAYS
	viewport.render_target_clear_mode = SubViewport.CLEAR_MODE_ALWAYS
	viewport.own_world_3d = true
	viewport.transparent_bg = false
	viewport.msaa_3d = Viewport.MSAA_DISABLED
	viewport.screen_space_aa = Viewport.SCREEN_SPACE_AA_DISABLED
	viewport.use_debanding = false
	viewport.scaling_3d_scale = 1.0
	add_child(viewport)

	sky = Sky.new()
	# The background pass runs the shader per pixel. The radiance map is not needed (no meshes), and
	# the sources below keep Godot from rendering it at all; the smallest size in case it does.
	sky.radiance_size = Sky.RADIANCE_SIZE_32
	environment = Environment.new()
	environment.background_mode = Environment.BG_SKY
	environment.sky = sky
	environment.ambient_light_source = Environment.AMBIENT_SOURCE_DISABLED
	environment.reflected_light_source = Environment.REFLECTION_SOURCE_DISABLED
	environment.tonemap_mode = Environment.TONE_MAPPER_LINEAR
	environment.tonemap_exposure = 1.0
	environment.tonemap_white = 1.0
	environment.glow_enabled = false
	environment.fog_enabled = false
	environment.volumetric_fog_enabled = false
	environment.adjustment_enabled = false
	var world_environment := WorldEnvironment.new()
	world_environment.environment = environment
	viewport.add_child(world_environment)

	camera = Camera3D.new()
	camera.keep_aspect = Camera3D.KEEP_HEIGHT
	camera.projection = Camera3D.PROJECTION_PERSPECTIVE
	viewport.add_child(camera)
	camera.current = true

	sun = DirectionalLight3D.new()
	sun.shadow_enabled = false
	sun.sky_mode = DirectionalLight3D.SKY_MODE_LIGHT_AND_SKY
	viewport.add_child(sun)

	bridge = JavaScriptBridge.get_interface("oracle")
	var info := {
		"version": Engine.get_version_info().string,
		"rendering_method": RenderingServer.get_current_rendering_method(),
		"adapter": RenderingServer.get_video_adapter_name(),
		"vendor": RenderingServer.get_video_adapter_vendor(),
		"api": RenderingServer.get_video_adapter_api_version(),
	}
	bridge.ready(JSON.stringify(info))


func _process(_delta: float) -> void:
	if busy:
		return
	var text = bridge.take()
	if typeof(text) != TYPE_STRING or text == "":
		return
	busy = true
	_run(text)


func _run(text: String) -> void:
	var started := Time.get_ticks_usec()
	var job = JSON.parse_string(text)
	var reply := {}
	if typeof(job) != TYPE_DICTIONARY:
		reply = {"error": "the job is not a JSON object"}
	elif job.get("op") == "render":
		reply = await _render(job)
	elif job.get("op") == "compile":
		reply = await _compile(job)
	elif job.get("op") == "noise":
		reply = await _noise(job)
	elif job.get("op") == "ramp":
		reply = _ramp(job)
	elif job.get("op") == "defaults":
		reply = _defaults(job)
	else:
		reply = {"error": "unknown op %s" % str(job.get("op"))}
	if typeof(job) == TYPE_DICTIONARY:
		reply["id"] = job.get("id")
	reply["godot_ms"] = (Time.get_ticks_usec() - started) / 1000.0
	bridge.put(JSON.stringify(reply))
	busy = false


## A new Shader per distinct code, so that a compile job always compiles and reports its errors.
func _use_shader(code: String, force_new: bool) -> void:
	if force_new or shader == null or shader.code != code:
		shader = Shader.new()
		shader.code = code
	# A fresh material each job: uniforms not overridden by the job are back at their defaults.
	var material := ShaderMaterial.new()
	material.shader = shader
	sky.sky_material = material


func _compile(job: Dictionary) -> Dictionary:
	viewport.size = Vector2i(4, 4)
	_use_shader(str(job.get("code", "")), true)
	# Godot parses the shader when its code is set; the GLSL is built when the sky is first drawn.
	for i in 2:
		await RenderingServer.frame_post_draw
	return {"compiled": true}


func _uniform_value(uniform: Dictionary):
	var v: Array = uniform.get("value", [])
	match str(uniform.get("type")):
		"float":
			return float(v[0])
		"int", "uint":
			return int(v[0])
		"bool":
			return bool(v[0])
		"vec2":
			return Vector2(v[0], v[1])
		"vec3":
			return Vector3(v[0], v[1], v[2])
		"vec4":
			return Vector4(v[0], v[1], v[2], v[3])
		"ivec2":
			return Vector2i(int(v[0]), int(v[1]))
		"ivec3":
			return Vector3i(int(v[0]), int(v[1]), int(v[2]))
		"ivec4":
			return Vector4i(int(v[0]), int(v[1]), int(v[2]), int(v[3]))
		"color":
			return Color(v[0], v[1], v[2], v[3])
		"float_array":
			return PackedFloat32Array(v)
		"int_array":
			var ints := PackedInt32Array()
			for x in v:
				ints.append(int(x))
			return ints
		"noise_texture_2d", "ramp_texture":
			# Built by _render (a noise texture's generation takes frames).
			return null
		"texture_rgbaf":
			# [width, height, base64 of little-endian f32 RGBA, row 0 first]; the crate checked the
			# sizes, and create_from_data refuses (null) a byte count that does not match them.
			var bytes := Marshalls.base64_to_raw(str(v[2]))
			var image := Image.create_from_data(int(v[0]), int(v[1]), false, Image.FORMAT_RGBAF, bytes)
			if image == null:
				return null
			return ImageTexture.create_from_image(image)
		"cube_rgbaf":
			# [side, base64 of six faces of little-endian f32 RGBA, +X, -X, +Y, -Y, +Z, -Z, each
			# row 0 first]: Cubemap's layer order.
			var side := int(v[0])
			var all := Marshalls.base64_to_raw(str(v[1]))
			var face_bytes := side * side * 16
			if all.size() != face_bytes * 6:
				return null
			var images: Array[Image] = []
			for f in 6:
				var face := all.slice(f * face_bytes, (f + 1) * face_bytes)
				var image := Image.create_from_data(side, side, false, Image.FORMAT_RGBAF, face)
				if image == null:
					return null
				images.append(image)
			var cube := Cubemap.new()
			if cube.create_from_images(images) != OK:
				return null
			return cube
	return null


func _render(job: Dictionary) -> Dictionary:
	var width := int(job.get("width", 64))
	var height := int(job.get("height", 32))
	viewport.size = Vector2i(width, height)
	_use_shader(str(job.get("code", "")), false)
	var material: ShaderMaterial = sky.sky_material
	var declared := {}
	for property in shader.get_shader_uniform_list():
		declared[property.get("name")] = true
	for uniform in job.get("uniforms", []):
		# set_shader_parameter ignores unknown names: say so rather than render the defaults.
		if not declared.has(str(uniform.get("name"))):
			return {"error": "the shader declares no uniform named %s" % uniform.get("name")}
		var value = _uniform_value(uniform)
		if str(uniform.get("type")) == "noise_texture_2d":
			var made = await _generated_noise(uniform.get("value", {}), false, int(job.get("timeout_ms", 60000)))
			if typeof(made) == TYPE_STRING:
				return {"error": "uniform %s: %s" % [uniform.get("name"), made]}
			value = made
		if str(uniform.get("type")) == "ramp_texture":
			var built = _generated_ramp(uniform.get("value", {}))
			if typeof(built) == TYPE_STRING:
				return {"error": "uniform %s: %s" % [uniform.get("name"), built]}
			value = built
		if value == null:
			return {"error": "uniform %s: unsupported type %s, or texture data that does not match its size" % [uniform.get("name"), uniform.get("type")]}
		material.set_shader_parameter(str(uniform.get("name")), value)

	var cam: Dictionary = job.get("camera", {})
	camera.fov = float(cam.get("fov_deg", 90.0))
	# Node3D's default rotation order is YXZ: yaw about Y, then pitch about X.
	camera.rotation_degrees = Vector3(float(cam.get("pitch_deg", 0.0)), float(cam.get("yaw_deg", 0.0)), 0.0)
	var p: Array = cam.get("position", [0.0, 0.0, 0.0])
	camera.position = Vector3(p[0], p[1], p[2])

	var light = job.get("sun")
	if typeof(light) == TYPE_DICTIONARY:
		sun.visible = true
		# Basis z (LIGHT0_DIRECTION) = R_y(180 - a) R_x(-e) (0, 0, 1) = (cos e sin a, sin e, -cos e cos a).
		var e := float(light.get("elevation_deg", 0.0))
		var a := float(light.get("azimuth_deg", 0.0))
		sun.rotation_degrees = Vector3(-e, 180.0 - a, 0.0)
		var c: Array = light.get("color", [1.0, 1.0, 1.0])
		sun.light_color = Color(c[0], c[1], c[2])
		sun.light_energy = float(light.get("energy", 1.0))
		sun.light_angular_distance = float(light.get("angular_diameter_deg", 0.0))
	else:
		sun.visible = false

	var energies: Array = job.get("energies", [1.0])
	var frames := []
	var frame_ms := []
	# Frames rendered before the first capture. Measured: none is needed (a new shader, size, camera
	# or energy shows in the very next frame), so the crate sends 0.
	for i in int(job.get("settle_frames", 0)):
		environment.background_energy_multiplier = float(energies[0])
		await RenderingServer.frame_post_draw
	for energy in energies:
		environment.background_energy_multiplier = float(energy)
		var t0 := Time.get_ticks_usec()
		await RenderingServer.frame_post_draw
		var image := viewport.get_texture().get_image()
		if image == null:
			return {"error": "the viewport returned no image"}
		if image.get_width() != width or image.get_height() != height:
			return {"error": "the viewport gave a %dx%d image for a %dx%d job" % [image.get_width(), image.get_height(), width, height]}
		if image.get_format() != Image.FORMAT_RGBA8:
			image.convert(Image.FORMAT_RGBA8)
		frames.append(Marshalls.raw_to_base64(image.get_data()))
		frame_ms.append((Time.get_ticks_usec() - t0) / 1000.0)
	return {"width": width, "height": height, "frames": frames, "frame_ms": frame_ms}


## Sets properties of `object` from a JSON map in the order given, converting JSON numbers and
## arrays to each property's type. Returns an error message, or "" when all were set.
func _set_properties(object: Object, properties: Dictionary, order: Array) -> String:
	var types := {}
	for property in object.get_property_list():
		types[property.get("name")] = int(property.get("type"))
	var names: Array = order.filter(func(n): return properties.has(n))
	for name in properties:
		if not names.has(name):
			names.append(name)
	for name in names:
		if not types.has(name):
			return "%s has no property named %s" % [object.get_class(), name]
		var v = properties[name]
		if not _json_fits(v, types[name]):
			return "%s.%s cannot take the value %s" % [object.get_class(), name, str(v)]
		match types[name]:
			TYPE_INT:
				v = int(v)
			TYPE_FLOAT:
				v = float(v)
			TYPE_BOOL:
				v = bool(v)
			TYPE_VECTOR2:
				v = Vector2(v[0], v[1])
			TYPE_VECTOR3:
				v = Vector3(v[0], v[1], v[2])
			TYPE_PACKED_FLOAT32_ARRAY:
				v = PackedFloat32Array(v)
			TYPE_PACKED_COLOR_ARRAY:
				var colors := PackedColorArray()
				for c in v:
					colors.append(Color(c[0], c[1], c[2], c[3]))
				v = colors
			_:
				return "%s.%s has a type the oracle does not set" % [object.get_class(), name]
		object.set(name, v)
		# set() ignores a value it cannot convert: check that it took.
		if typeof(object.get(name)) != types[name]:
			return "%s.%s did not take the value %s" % [object.get_class(), name, str(properties[name])]
	return ""


## Whether a JSON value has the shape a property of Variant type `type` needs (JSON numbers
## arrive as floats; an integer property takes a whole number).
func _json_fits(v, type: int) -> bool:
	var number := func(x): return typeof(x) == TYPE_FLOAT or typeof(x) == TYPE_INT
	match type:
		TYPE_INT:
			return number.call(v) and float(v) == floor(float(v))
		TYPE_FLOAT:
			return number.call(v)
		TYPE_BOOL:
			return typeof(v) == TYPE_BOOL
		TYPE_VECTOR2:
			return typeof(v) == TYPE_ARRAY and v.size() == 2 and v.all(number)
		TYPE_VECTOR3:
			return typeof(v) == TYPE_ARRAY and v.size() == 3 and v.all(number)
		TYPE_PACKED_FLOAT32_ARRAY:
			return typeof(v) == TYPE_ARRAY and v.all(number)
		TYPE_PACKED_COLOR_ARRAY:
			return typeof(v) == TYPE_ARRAY and v.all(func(c): return typeof(c) == TYPE_ARRAY and c.size() == 4 and c.all(number))
	return false


## A NoiseTexture2D (or 3D) built from {"texture": {...}, "noise": {...} or null,
## "color_ramp": {...} or null}, after Godot has generated it; or an error message.
func _generated_noise(spec: Dictionary, volume: bool, limit_ms: int):
	var texture = NoiseTexture3D.new() if volume else NoiseTexture2D.new()
	var error := _set_properties(texture, spec.get("texture", {}), [])
	if error != "":
		return error
	var ramp = spec.get("color_ramp")
	if typeof(ramp) == TYPE_DICTIONARY:
		var gradient := Gradient.new()
		# Offsets first: set_colors and set_offsets each resize the point list.
		error = _set_properties(gradient, ramp, ["offsets", "colors"])
		if error != "":
			return error
		texture.color_ramp = gradient
	var noise = spec.get("noise")
	if typeof(noise) != TYPE_DICTIONARY:
		return "no noise: Godot generates nothing without one"
	var fnl := FastNoiseLite.new()
	error = _set_properties(fnl, noise, [])
	if error != "":
		return error
	texture.noise = fnl
	# The first generation runs in a deferred call at the end of this frame (synchronously, not on
	# a thread: NoiseTexture2D::_update_texture's first_time), then emits `changed`.
	var done := [false]
	texture.changed.connect(func(): done[0] = true)
	var started := Time.get_ticks_msec()
	while not done[0]:
		if Time.get_ticks_msec() - started > limit_ms:
			return "Godot did not generate the noise texture within %d ms" % limit_ms
		await get_tree().process_frame
	return texture


## NoiseTexture3D::_modulate_with_gradient: each texel's luminance through the gradient.
func _modulate(image: Image, gradient: Gradient) -> Image:
	var out := Image.create_empty(image.get_width(), image.get_height(), false, Image.FORMAT_RGBA8)
	for y in image.get_height():
		for x in image.get_width():
			out.set_pixel(x, y, gradient.sample(image.get_pixel(x, y).get_luminance()))
	return out


func _format_name(format: int) -> String:
	match format:
		Image.FORMAT_L8:
			return "L8"
		Image.FORMAT_RGBA8:
			return "RGBA8"
		Image.FORMAT_RGB8:
			return "RGB8"
		Image.FORMAT_RGBAF:
			return "RGBAF"
		Image.FORMAT_RGBAH:
			return "RGBAH"
		Image.FORMAT_RGBF:
			return "RGBF"
		Image.FORMAT_RF:
			return "RF"
	return "format %d" % format


## Level 0 of each image, base64, with the format Godot generated and whether it had mipmaps.
func _noise(job: Dictionary) -> Dictionary:
	var volume := bool(job.get("volume", false))
	var made = await _generated_noise(job.get("spec", {}), volume, int(job.get("timeout_ms", 60000)))
	if typeof(made) == TYPE_STRING:
		return {"error": made}
	var images := []
	if volume:
		# Not made.get_data(): the Compatibility renderer's texture_3d_get on WebGL2 hands back
		# wrong slices (measured: slices 0, 0, 1, 3, 3, 4 of a depth-6 texture). These are the
		# calls NoiseTexture3D::_generate_texture makes, with its colour ramp step.
		var t: NoiseTexture3D = made
		if t.seamless:
			images = t.noise.get_seamless_image_3d(t.width, t.height, t.depth, t.invert, t.seamless_blend_skirt, t.normalize)
		else:
			images = t.noise.get_image_3d(t.width, t.height, t.depth, t.invert, t.normalize)
		if t.color_ramp != null:
			images = images.map(func(image): return _modulate(image, t.color_ramp))
	else:
		images = [made.get_image()]
	if images.is_empty() or images[0] == null:
		return {"error": "Godot generated no image"}
	var layers := []
	var mipmaps := false
	for image in images:
		var level0: Image = image
		if image.has_mipmaps():
			mipmaps = true
			level0 = image.duplicate()
			level0.clear_mipmaps()
		layers.append(Marshalls.raw_to_base64(level0.get_data()))
	var first: Image = images[0]
	# Levels 1… as Godot stores them after level 0 (a 2D image only).
	var mip_data := ""
	if not volume and first.get_mipmap_count() > 0:
		mip_data = Marshalls.raw_to_base64(first.get_data().slice(first.get_mipmap_offset(1)))
	return {"width": first.get_width(), "height": first.get_height(), "format": _format_name(first.get_format()), "mipmaps": mipmaps, "layers": layers, "mip_data": mip_data}


## A GradientTexture1D, GradientTexture2D or CurveTexture built from {"class": ..., "texture":
## {...}, "gradient": {...} or null, "curve": {...} or null}; or an error message.
func _generated_ramp(spec: Dictionary):
	var name := str(spec.get("class", ""))
	if not name in ["GradientTexture1D", "GradientTexture2D", "CurveTexture", "CurveXYZTexture"]:
		return "the oracle does not build a %s" % name
	var texture = ClassDB.instantiate(name)
	var error := ""
	var g = spec.get("gradient")
	if typeof(g) == TYPE_DICTIONARY:
		var gradient := Gradient.new()
		# Offsets first: set_colors and set_offsets each resize the point list.
		error = _set_properties(gradient, g, ["offsets", "colors"])
		if error != "":
			return error
		texture.gradient = gradient
	for key in ["curve", "curve_x", "curve_y", "curve_z"]:
		var c = spec.get(key)
		if typeof(c) == TYPE_DICTIONARY:
			texture.set(key, _curve(c))
	error = _set_properties(texture, spec.get("texture", {}), [])
	if error != "":
		return error
	return texture


## A Curve as loading a .tres makes one: `_limits` [min_value, max_value, min_domain,
## max_domain] and `bake_resolution`, then `_data` (x, y, left and right tangent, left and right
## mode per point), stored as given: no tangent is recomputed from its mode.
func _curve(c: Dictionary) -> Curve:
	var curve := Curve.new()
	curve.set("_limits", [float(c.get("min_value", 0.0)), float(c.get("max_value", 1.0)), float(c.get("min_domain", 0.0)), float(c.get("max_domain", 1.0))])
	curve.bake_resolution = int(c.get("bake_resolution", 100))
	var data := []
	for p in c.get("points", []):
		data.append_array([Vector2(p[0], p[1]), float(p[2]), float(p[3]), int(p[4]), int(p[5])])
	curve.set("_data", data)
	return curve


## The image of a gradient or curve texture, base64, in Godot's format.
func _ramp(job: Dictionary) -> Dictionary:
	var made = _generated_ramp(job.get("spec", {}))
	if typeof(made) == TYPE_STRING:
		return {"error": made}
	var image: Image = null
	var quantized := false
	if made is CurveTexture:
		# CurveTexture has no get_image() (Texture2D's returns null) and reading the float
		# texture back through WebGL2 would go through 8-bit pixels: build the image
		# CurveTexture::_update builds, from the same Curve.sample_baked calls at i / width.
		var t: CurveTexture = made
		var red := t.texture_mode == CurveTexture.TEXTURE_MODE_RED
		var values := PackedFloat32Array()
		for i in t.width:
			var v := 0.0
			if t.curve != null:
				v = t.curve.sample_baked(i / float(t.width))
			values.append(v)
			if not red:
				values.append(v)
				values.append(v)
		image = Image.create_from_data(t.width, 1, false, Image.FORMAT_RF if red else Image.FORMAT_RGBF, values.to_byte_array())
	elif made is GradientTexture1D and made.use_hdr:
		# Reading an RGBAF texture back through WebGL2 goes through 8-bit pixels (measured:
		# values clamped to 0 … 1 and rounded to 1/255): build the image
		# GradientTexture1D::_update builds, from the same Gradient.sample calls.
		var t: GradientTexture1D = made
		if t.gradient != null:
			image = Image.create_empty(t.width, 1, false, Image.FORMAT_RGBAF)
			for i in t.width:
				image.set_pixel(i, 0, t.gradient.sample(i / float(t.width - 1)))
	elif made is CurveXYZTexture:
		# As for a CurveTexture: CurveXYZTexture::_update's sample_baked calls, in RGBF.
		var t: CurveXYZTexture = made
		var values := PackedFloat32Array()
		for i in t.width:
			for curve in [t.curve_x, t.curve_y, t.curve_z]:
				values.append(0.0 if curve == null else curve.sample_baked(i / float(t.width)))
		image = Image.create_from_data(t.width, 1, false, Image.FORMAT_RGBF, values.to_byte_array())
	else:
		# A GradientTexture2D with use_hdr comes back through 8-bit pixels (see above); the
		# reply says so, and its offsets are not reachable from GDScript.
		image = made.get_image()
		quantized = made is GradientTexture2D and made.use_hdr
	if image == null:
		return {"error": "Godot generated no image"}
	return {"width": image.get_width(), "height": image.get_height(), "format": _format_name(image.get_format()), "data": Marshalls.raw_to_base64(image.get_data()), "quantized": quantized}


## The values a new instance of a class has for the named properties (Vector3 and packed arrays
## as JSON arrays, objects as their class name).
func _defaults(job: Dictionary) -> Dictionary:
	var name := str(job.get("class", ""))
	if not ClassDB.can_instantiate(name):
		return {"error": "cannot instantiate %s" % name}
	var object = ClassDB.instantiate(name)
	var values := {}
	for property in job.get("properties", []):
		var v = object.get(property)
		match typeof(v):
			TYPE_VECTOR2:
				v = [v.x, v.y]
			TYPE_VECTOR3:
				v = [v.x, v.y, v.z]
			TYPE_PACKED_FLOAT32_ARRAY:
				v = Array(v)
			TYPE_PACKED_COLOR_ARRAY:
				var colors := []
				for c in v:
					colors.append([c.r, c.g, c.b, c.a])
				v = colors
			TYPE_OBJECT:
				v = v.get_class() if v != null else null
		values[property] = v
	return {"values": values}
