//! The f64 routines of gdsky's f64 evaluation (`gdsky_naga::F64_MATH_WGSL`: exp, log, sin, …,
//! the functions SPIR-V has no f64 form of), run on the Vulkan device (lavapipe without a GPU)
//! in a compute shader built as gdsky's f64 modules are (naga's SPIR-V decorated `NoContraction`,
//! passed to the driver as is), and compared with Rust's f64 methods over each routine's domain
//! (for acosh and atanh, fdlibm's formulas over Rust's `ln_1p`: Rust's own lose up to 200 ulps,
//! see their cases). Prints the error table of docs/precision.md (max and mean error in ulps of
//! the reference) and fails when a routine's worst error exceeds its bound.

use wgpu::util::DeviceExt;

/// (x range, y range, log-uniform in |x|).
type Domain = ((f64, f64), (f64, f64), bool);

/// One routine under test: its WGSL name, arity, the Rust reference, input ranges, and the
/// bound on its worst error in ulps.
struct Case {
    name: &'static str,
    reference: fn(f64, f64) -> f64,
    /// (x range, y range, log-uniform in |x|); y is ignored by unary routines.
    domains: &'static [Domain],
    bound: f64,
}

/// sin, cos and tan: small arguments, the three-piece reduction's range (< 1.6e6) and the
/// seven-piece one's up to 2^53 (log-uniform, both signs).
const TRIG_DOMAINS: &[Domain] = &[
    ((-10.0, 10.0), (0.0, 0.0), false),
    ((-1e5, 1e5), (0.0, 0.0), false),
    ((1e5, 1e9), (0.0, 0.0), true),
    ((1e9, 9e15), (0.0, 0.0), true),
];

const CASES: &[Case] = &[
    Case {
        name: "exp",
        reference: |x, _| x.exp(),
        domains: &[((-1.0, 1.0), (0.0, 0.0), false), ((-708.0, 709.0), (0.0, 0.0), false)],
        bound: 2.0,
    },
    Case {
        name: "exp2",
        reference: |x, _| x.exp2(),
        domains: &[((-1.0, 1.0), (0.0, 0.0), false), ((-1020.0, 1023.0), (0.0, 0.0), false)],
        bound: 2.0,
    },
    Case {
        name: "log",
        reference: |x, _| x.ln(),
        domains: &[((0.5, 2.0), (0.0, 0.0), false), ((1e-300, 1e300), (0.0, 0.0), true)],
        bound: 2.0,
    },
    Case {
        name: "log2",
        reference: |x, _| x.log2(),
        domains: &[((0.5, 2.0), (0.0, 0.0), false), ((1e-300, 1e300), (0.0, 0.0), true)],
        bound: 3.0,
    },
    Case {
        name: "pow",
        reference: |x, y| x.powf(y),
        domains: &[((0.0, 2.0), (-3.0, 3.0), false), ((1e-10, 1e10), (-30.0, 30.0), true)],
        bound: 2.0,
    },
    Case { name: "sin", reference: |x, _| x.sin(), domains: TRIG_DOMAINS, bound: 2.0 },
    Case { name: "cos", reference: |x, _| x.cos(), domains: TRIG_DOMAINS, bound: 2.0 },
    Case { name: "tan", reference: |x, _| x.tan(), domains: TRIG_DOMAINS, bound: 4.0 },
    Case { name: "asin", reference: |x, _| x.asin(), domains: &[((-1.0, 1.0), (0.0, 0.0), false)], bound: 4.0 },
    Case { name: "acos", reference: |x, _| x.acos(), domains: &[((-1.0, 1.0), (0.0, 0.0), false)], bound: 4.0 },
    Case {
        name: "atan",
        reference: |x, _| x.atan(),
        domains: &[((-4.0, 4.0), (0.0, 0.0), false), ((1e-10, 1e10), (0.0, 0.0), true)],
        bound: 2.0,
    },
    Case { name: "atan2", reference: |y, x| y.atan2(x), domains: &[((-10.0, 10.0), (-10.0, 10.0), false)], bound: 4.0 },
    Case {
        name: "sinh",
        reference: |x, _| x.sinh(),
        domains: &[((-2.0, 2.0), (0.0, 0.0), false), ((-700.0, 700.0), (0.0, 0.0), false)],
        bound: 4.0,
    },
    Case {
        name: "cosh",
        reference: |x, _| x.cosh(),
        domains: &[((-2.0, 2.0), (0.0, 0.0), false), ((-700.0, 700.0), (0.0, 0.0), false)],
        bound: 4.0,
    },
    Case { name: "tanh", reference: |x, _| x.tanh(), domains: &[((-20.0, 20.0), (0.0, 0.0), false)], bound: 4.0 },
    Case {
        name: "asinh",
        reference: |x, _| x.asinh(),
        domains: &[((-2.0, 2.0), (0.0, 0.0), false), ((1e-10, 1e10), (0.0, 0.0), true)],
        bound: 4.0,
    },
    Case {
        name: "acosh",
        // Not Rust's `acosh`: it is ln(x + √(x − 1)·√(x + 1)), which loses up to 28 ulps near 1
        // (measured against mpmath at 120 bits, 20,000 inputs); fdlibm's form with Rust's ln_1p
        // is within 2 ulps of mpmath on [1, 3] and 1 on [1, 1e10].
        reference: |x, _| {
            let t = x - 1.0;
            (t + (2.0 * t + t * t).sqrt()).ln_1p()
        },
        domains: &[((1.0, 3.0), (0.0, 0.0), false), ((1.0, 1e10), (0.0, 0.0), true)],
        bound: 4.0,
    },
    Case {
        name: "atanh",
        // Not Rust's `atanh`: ½·ln_1p(2x/(1 − x)) rounds 1 − x for negative x and loses up to 200
        // ulps near −1 (mpmath, 20,000 inputs); on |x| (where 1 − |x| is exact from ½ up) it is
        // within 1 ulp of mpmath.
        reference: |x, _| {
            let a = x.abs();
            (0.5 * ((a + a) / (1.0 - a)).ln_1p()).copysign(x)
        },
        domains: &[((-0.999, 0.999), (0.0, 0.0), false)],
        bound: 4.0,
    },
];

/// Inputs per domain.
const N: usize = 1 << 14;

/// The distance from `got` to `want` in ulps of `want` (0 when both are the same NaN class or
/// the same infinity; infinite when one is NaN and the other not).
fn ulps(got: f64, want: f64) -> f64 {
    if got.is_nan() || want.is_nan() {
        return if got.is_nan() && want.is_nan() { 0.0 } else { f64::INFINITY };
    }
    if got == want {
        return 0.0;
    }
    if want.is_infinite() || got.is_infinite() {
        return f64::INFINITY;
    }
    let exp = if want == 0.0 { -1022 } else { (want.abs().log2().floor() as i32).max(-1022) };
    // ulp = 2^(exp − 52) in two factors: 2f64.powi(n) for n < −1022 overflows its reciprocal
    // (it is 1/2^−n = 1/inf = 0), which read every result below about 1e−296 as inf ulps off.
    (got - want).abs() / (2f64.powi(exp) * 2f64.powi(-52))
}

/// xorshift64*: reproducible inputs without a dependency.
struct Rng(u64);
impl Rng {
    fn unit(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn in_range(&mut self, (lo, hi): (f64, f64), log: bool) -> f64 {
        if log { (lo.ln() + self.unit() * (hi.ln() - lo.ln())).exp() } else { lo + self.unit() * (hi - lo) }
    }
}

fn shader() -> String {
    let mut arms = String::new();
    for (i, c) in CASES.iter().enumerate() {
        let call = if matches!(c.name, "pow" | "atan2") {
            format!("gdsky_f64_{}(v.x, v.y)", c.name)
        } else {
            format!("gdsky_f64_{}(v.x)", c.name)
        };
        arms.push_str(&format!("        case {i}u: {{ r = {call}; }}\n"));
    }
    format!(
        "{}\n@group(0) @binding(0) var<storage, read> inputs: array<vec2<f64>>;\n\
         @group(0) @binding(1) var<storage, read_write> outputs: array<f64>;\n\
         @group(0) @binding(2) var<uniform> routine: vec4<u32>;\n\
         @compute @workgroup_size(64)\n\
         fn main(@builtin(global_invocation_id) id: vec3<u32>) {{\n\
             let i = id.x;\n\
             if (i >= arrayLength(&inputs)) {{ return; }}\n\
             let v = inputs[i];\n\
             var r = 0.0lf;\n\
             switch routine.x {{\n{arms}        default: {{}}\n    }}\n\
             outputs[i] = r;\n\
         }}\n",
        gdsky_naga::F64_MATH_WGSL
    )
}

/// The compute pipeline of `wgsl` as gdsky's f64 modules reach the driver: naga's SPIR-V with
/// every float operation decorated `NoContraction` (`gdsky_naga::exact_arithmetic`), passed
/// through as is; `spirv-val` checks the binary first.
fn exact_pipeline(gpu: &skyrun::Gpu, wgsl: &str) -> wgpu::ComputePipeline {
    assert!(gpu.has_passthrough(), "the device cannot take SPIR-V as is (PASSTHROUGH_SHADERS)");
    let module = naga::front::wgsl::parse_str(wgsl).expect("the routines parse");
    let info = gdsky_naga::validator_f64().validate(&module).expect("the routines validate");
    let options = naga::back::spv::Options { lang_version: (1, 3), ..Default::default() };
    let words = naga::back::spv::write_vec(&module, &info, &options, None).expect("SPIR-V");
    let words = gdsky_naga::exact_arithmetic(&words);
    crate::common::spirv_val(&words);
    let device = gpu.device();
    // SAFETY: a naga-validated module written by naga, decorated, and accepted by spirv-val.
    let module = unsafe {
        device.create_shader_module_passthrough(wgpu::ShaderModuleDescriptorPassthrough {
            label: Some("f64 math"),
            spirv: Some(words.into()),
            entry_points: vec![wgpu::PassthroughShaderEntryPoint { name: "main".into(), workgroup_size: (64, 1, 1) }]
                .into(),
            ..Default::default()
        })
    };
    let buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    let entries = [
        buffer(0, wgpu::BufferBindingType::Storage { read_only: true }),
        buffer(1, wgpu::BufferBindingType::Storage { read_only: false }),
        buffer(2, wgpu::BufferBindingType::Uniform),
    ];
    let group = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: None, entries: &entries });
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: None,
        bind_group_layouts: &[Some(&group)],
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("f64 math"),
        layout: Some(&layout),
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    })
}

/// Runs routine `index` on `inputs` on the device.
fn run(gpu: &skyrun::Gpu, pipeline: &wgpu::ComputePipeline, index: u32, inputs: &[[f64; 2]]) -> Vec<f64> {
    let device = gpu.device();
    let bytes: Vec<u8> = inputs.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("inputs"),
        contents: &bytes,
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (inputs.len() * 8) as u64;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("outputs"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let routine = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("routine"),
        contents: &[index, 0, 0, 0].iter().flat_map(|v: &u32| v.to_le_bytes()).collect::<Vec<u8>>(),
        usage: wgpu::BufferUsages::UNIFORM,
    });
    let bind = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: None,
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: input.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: output.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 2, resource: routine.as_entire_binding() },
        ],
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor::default());
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind, &[]);
        pass.dispatch_workgroups((inputs.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, size);
    gpu.queue().submit([encoder.finish()]);
    readback.map_async(wgpu::MapMode::Read, .., |r| r.expect("map"));
    device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).expect("poll");
    let view = readback.get_mapped_range(..).expect("mapped");
    view.chunks_exact(8).map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes"))).collect()
}

#[test]
fn f64_routines_match_rust_to_a_few_ulps_on_the_gpu() {
    let gpu = crate::common::gpu();
    assert!(gpu.has_f64(), "the device has no f64 shaders (SHADER_F64)");
    let pipeline = exact_pipeline(&gpu, &shader());
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut failures = Vec::new();
    eprintln!("| routine | domain | max ulp | mean ulp | worst input → result |");
    eprintln!("|---|---|---|---|---|");
    for (index, case) in CASES.iter().enumerate() {
        for &(xr, yr, log) in case.domains {
            let mut inputs: Vec<[f64; 2]> = (0..N).map(|_| [rng.in_range(xr, log), rng.in_range(yr, false)]).collect();
            if log && case.name != "acosh" {
                // Both signs of a log-uniform magnitude, except where the domain is one-sided.
                let one_sided = matches!(case.name, "log" | "log2" | "pow");
                if !one_sided {
                    for (i, v) in inputs.iter_mut().enumerate() {
                        if i % 2 == 1 {
                            v[0] = -v[0];
                        }
                    }
                }
            }
            let got = run(&gpu, &pipeline, index as u32, &inputs);
            let (mut max, mut sum, mut worst, mut worst_got) = (0.0f64, 0.0f64, [0.0; 2], 0.0f64);
            for (v, g) in inputs.iter().zip(&got) {
                let e = ulps(*g, (case.reference)(v[0], v[1]));
                sum += e;
                if e > max || e.is_nan() {
                    max = e;
                    worst = *v;
                    worst_got = *g;
                }
            }
            let mean = sum / N as f64;
            let domain = if matches!(case.name, "pow" | "atan2") {
                format!("x∈[{:e}, {:e}]{}, y∈[{}, {}]", xr.0, xr.1, if log { " log" } else { "" }, yr.0, yr.1)
            } else {
                format!("[{:e}, {:e}]{}", xr.0, xr.1, if log { " log-uniform, ±" } else { "" })
            };
            eprintln!("| {} | {domain} | {max:.2} | {mean:.3} | {:?} → {worst_got:e} |", case.name, worst);
            if max.is_nan() || max > case.bound {
                failures.push(format!("{} on {domain}: {max:.2} ulps > {} at {:?}", case.name, case.bound, worst));
            }
        }
    }
    // Special values follow the GLSL / C99 conventions the routines document.
    let specials: &[(u32, [f64; 2], f64)] = &[
        (0, [f64::INFINITY, 0.0], f64::INFINITY),
        (0, [-f64::INFINITY, 0.0], 0.0),
        (0, [800.0, 0.0], f64::INFINITY),
        (2, [0.0, 0.0], -f64::INFINITY),
        (2, [-1.0, 0.0], f64::NAN),
        (2, [f64::INFINITY, 0.0], f64::INFINITY),
        (4, [0.0, 2.0], 0.0),
        (4, [0.0, -2.0], f64::INFINITY),
        (4, [2.0, 0.0], 1.0),
        (4, [1.0, f64::NAN], 1.0),
        (4, [-2.0, 2.0], f64::NAN),
        // sin beyond 2^53 (no Payne–Hanek) and of infinity: NaN, not a wrong value.
        (5, [1e16, 0.0], f64::NAN),
        (5, [f64::INFINITY, 0.0], f64::NAN),
        (4, [2.0, 1100.0], f64::INFINITY),
        (8, [1.0, 0.0], std::f64::consts::FRAC_PI_2),
        (9, [-1.0, 0.0], std::f64::consts::PI),
        (11, [0.0, -1.0], std::f64::consts::PI),
        (11, [1.0, 0.0], std::f64::consts::FRAC_PI_2),
        (17, [1.0, 0.0], f64::INFINITY),
    ];
    for &(index, input, want) in specials {
        let got = run(&gpu, &pipeline, index, &[input])[0];
        if ulps(got, want) > 1.0 {
            failures.push(format!("{}({input:?}) = {got}, want {want}", CASES[index as usize].name));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
