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
		"texture_rgbaf":
			# [width, height, base64 of little-endian f32 RGBA, row 0 first]; the crate checked the
			# sizes, and create_from_data refuses (null) a byte count that does not match them.
			var bytes := Marshalls.base64_to_raw(str(v[2]))
			var image := Image.create_from_data(int(v[0]), int(v[1]), false, Image.FORMAT_RGBAF, bytes)
			if image == null:
				return null
			return ImageTexture.create_from_image(image)
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
