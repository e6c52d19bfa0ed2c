//! regatta-gpu: the wgpu backend. It renders the paper-mode flat views of every Panoramic
//! turret (two 75×7 views, optional `samples`² supersampling) and the strip of every K213, for
//! many robots in many independent worlds, in one GPU submission per update, and reads back
//! only the photocurrents (150 per retina, one per K213 pixel).
//!
//! The GPU ray-casts the render graph (`retina.wgsl`): exact intersections with the analytic
//! primitives and mesh triangles, the VRML97 lighting model, shadow rays, the 8-bit frame
//! buffer when `quantizeViews` asks for it, then the warp to the cylinder and the vertical
//! average in a second compute pass. Normalisation, filters and conversion stay on the CPU,
//! shared with the CPU renderer. Pipelines and scene buffers are built once; batch buffers
//! grow and are reused.
//!
//! Vision devices are rendered in paper mode only: a turret whose world asks for exact
//! optics is drawn with paper optics here ([`GpuVision::exact_turrets`] lists them).

mod pack;

use std::sync::mpsc;

use glam::DVec3;
use regatta_runtime::optics::{FLAT_COLUMNS, FLAT_ROWS, VIEW_CENTERS};
use regatta_runtime::retina::PIXELS;
use regatta_runtime::vision::{VisionBackend, VisionError, VisionRequest, WorldInstance};
use regatta_runtime::Compiled;
use wgpu::util::DeviceExt;

use pack::{Device, GpuView, Packed, SceneInfo};

const FLAT_PIXELS: u32 = (FLAT_COLUMNS * FLAT_ROWS) as u32;
const WORKGROUP: u32 = 64;
/// Storage buffers the shader binds: six of scene data, five of the batch.
const STORAGE_BUFFERS: u32 = 11;
/// Views per dispatch row: the limit of one dispatch dimension.
const ROW: u32 = 65_535;

/// Why the backend could not start.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter: wgpu found no Vulkan, Metal, DX12 or GL device ({0}). Install a driver \
         (for a software one, Mesa's lavapipe: `apt install mesa-vulkan-drivers libvulkan1`) or \
         use `--renderer cpu`"
    )]
    NoAdapter(String),
    #[error("the GPU adapter '{adapter}' refused a device: {why}")]
    Device { adapter: String, why: String },
}

/// A GPU adapter and the vision pipelines, with the scenes it was built for.
pub struct GpuVision {
    device: wgpu::Device,
    queue: wgpu::Queue,
    adapter: wgpu::AdapterInfo,
    trace: wgpu::ComputePipeline,
    warp: wgpu::ComputePipeline,
    scene_group: wgpu::BindGroup,
    batch_layout: wgpu::BindGroupLayout,
    infos: Vec<SceneInfo>,
    warp_table: u32,
    batch: Option<Batch>,
    // Reused between updates: no allocation once warm.
    views: Vec<GpuView>,
    instances: Vec<[u32; 4]>,
    poses: Vec<[f32; 4]>,
    outputs: Vec<(usize, usize)>,
}

/// Per-batch buffers, grown when a batch outgrows them.
struct Batch {
    capacity: Capacity,
    instances: wgpu::Buffer,
    poses: wgpu::Buffer,
    views: wgpu::Buffer,
    uniform: wgpu::Buffer,
    outputs: wgpu::Buffer,
    staging: wgpu::Buffer,
    group: wgpu::BindGroup,
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Capacity {
    instances: usize,
    poses: usize,
    views: usize,
    flat: usize,
    outputs: usize,
}

impl Capacity {
    fn holds(&self, need: &Capacity) -> bool {
        self.instances >= need.instances
            && self.poses >= need.poses
            && self.views >= need.views
            && self.flat >= need.flat
            && self.outputs >= need.outputs
    }

    /// Room for `need` with headroom, so that a slowly growing batch reallocates rarely.
    fn grown(&self, need: &Capacity) -> Capacity {
        let grow = |have: usize, need: usize| {
            if have >= need {
                have
            } else {
                need.next_power_of_two().max(16)
            }
        };
        Capacity {
            instances: grow(self.instances, need.instances),
            poses: grow(self.poses, need.poses),
            views: grow(self.views, need.views),
            flat: grow(self.flat, need.flat),
            outputs: grow(self.outputs, need.outputs),
        }
    }
}

fn storage_entry(binding: u32, read_only: bool) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer {
            ty: wgpu::BufferBindingType::Storage { read_only },
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

impl GpuVision {
    /// Finds an adapter and uploads `worlds`; a [`WorldInstance`]'s `scene` indexes them.
    pub fn new(worlds: &[&Compiled]) -> Result<GpuVision, GpuError> {
        let (device, queue, adapter) = pollster::block_on(open_device())?;
        let packed = pack::pack(worlds);
        Ok(GpuVision::build(device, queue, adapter, packed))
    }

    fn build(
        device: wgpu::Device,
        queue: wgpu::Queue,
        adapter: wgpu::AdapterInfo,
        packed: Packed,
    ) -> GpuVision {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("retina.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("retina.wgsl").into()),
        });
        let scene_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("scene"),
            entries: &(0..6).map(|b| storage_entry(b, true)).collect::<Vec<_>>(),
        });
        let batch_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("batch"),
            entries: &[
                storage_entry(0, true),
                storage_entry(1, true),
                storage_entry(2, true),
                storage_entry(3, false),
                storage_entry(4, false),
                wgpu::BindGroupLayoutEntry {
                    binding: 5,
                    visibility: wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("vision"),
            bind_group_layouts: &[Some(&scene_layout), Some(&batch_layout)],
            immediate_size: 0,
        });
        let pipeline = |entry: &str| {
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let (trace, warp) = (pipeline("trace_views"), pipeline("warp_views"));
        let upload = |label: &str, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let buffers = [
            upload("primitives", bytemuck::cast_slice(&packed.prims)),
            upload("materials", bytemuck::cast_slice(&packed.materials)),
            upload("lights", bytemuck::cast_slice(&packed.lights)),
            upload("scenes", bytemuck::cast_slice(&packed.scenes)),
            upload("triangles", bytemuck::cast_slice(&packed.triangles)),
            upload("tables", bytemuck::cast_slice(&packed.tables)),
        ];
        let entries: Vec<_> = buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect();
        let scene_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("scene"),
            layout: &scene_layout,
            entries: &entries,
        });
        GpuVision {
            device,
            queue,
            adapter,
            trace,
            warp,
            scene_group,
            batch_layout,
            infos: packed.infos,
            warp_table: packed.warp_table,
            batch: None,
            views: Vec::new(),
            instances: Vec::new(),
            poses: Vec::new(),
            outputs: Vec::new(),
        }
    }

    /// The adapter's name and API, e.g. `llvmpipe (LLVM 15.0.6, 256 bits), Vulkan`.
    pub fn adapter(&self) -> String {
        format!("{}, {:?}", self.adapter.name, self.adapter.backend)
    }

    /// Whether the adapter is a software rasteriser (llvmpipe, lavapipe, WARP…).
    pub fn is_software(&self) -> bool {
        self.adapter.device_type == wgpu::DeviceType::Cpu
    }

    /// Turrets (`robot/turret`) of scene `scene` whose world asks for exact optics: this
    /// backend renders them in paper mode.
    pub fn exact_turrets(&self, scene: usize) -> &[String] {
        self.infos
            .get(scene)
            .map_or(&[], |info| info.exact_turrets.as_slice())
    }

    /// Lays out the views of a batch; returns the flat-pixel and output counts.
    fn plan_batch(
        &mut self,
        instances: &[WorldInstance],
        requests: &[VisionRequest],
    ) -> Result<(usize, usize), VisionError> {
        self.views.clear();
        self.instances.clear();
        self.poses.clear();
        self.outputs.clear();
        for world in instances {
            let info = self
                .infos
                .get(world.scene)
                .ok_or_else(|| VisionError::BadRequest {
                    index: 0,
                    why: format!("scene {} does not exist", world.scene),
                })?;
            let first = (self.poses.len() / 2) as u32;
            let robots = world.poses.poses.len().min(info.robots.len());
            for (r, pose) in world.poses.poses.iter().take(robots).enumerate() {
                let floor = world
                    .poses
                    .floor_y
                    .get(r)
                    .copied()
                    .unwrap_or(info.robots[r].0);
                let at = DVec3::new(pose.x, floor, pose.z) - info.origin;
                self.poses
                    .push([at.x as f32, at.y as f32, at.z as f32, 0.0]);
                let (s, c) = (libm::sin(pose.heading), libm::cos(pose.heading));
                self.poses.push([c as f32, s as f32, 0.0, 0.0]);
            }
            self.instances
                .push([world.scene as u32, first, robots as u32, 0]);
        }
        let (mut flat, mut outputs) = (0usize, 0usize);
        for (index, request) in requests.iter().enumerate() {
            let bad = |why: String| VisionError::BadRequest { index, why };
            let world = instances
                .get(request.instance)
                .ok_or_else(|| bad(format!("instance {} does not exist", request.instance)))?;
            let info = &self.infos[world.scene];
            let pose = world
                .poses
                .poses
                .get(request.robot)
                .filter(|_| request.robot < info.robots.len())
                .ok_or_else(|| bad(format!("robot {} does not exist", request.robot)))?;
            let (floor, device) = &info.robots[request.robot];
            let floor = world
                .poses
                .floor_y
                .get(request.robot)
                .copied()
                .unwrap_or(*floor);
            let instance = request.instance as u32;
            let robot = request.robot as u32;
            let Some(device) = device else {
                return Err(bad(format!("robot {} has no vision device", request.robot)));
            };
            let (Device::Panoramic { height, .. } | Device::Linear { height, .. }) = device;
            let eye = DVec3::new(pose.x, floor + height, pose.z) - info.origin;
            let eye = [
                eye.x as f32,
                eye.y as f32,
                eye.z as f32,
                pose.heading as f32,
            ];
            match device {
                Device::Panoramic {
                    samples,
                    quantize,
                    columns,
                    rows,
                    ..
                } => {
                    for (v, center) in VIEW_CENTERS.iter().enumerate() {
                        self.views.push(GpuView {
                            a: [instance, robot, 0, (outputs + v * FLAT_COLUMNS) as u32],
                            b: [FLAT_PIXELS, *samples, *quantize as u32, flat as u32],
                            c: [*columns, *rows, v as u32, 0],
                            eye,
                            geo: [*center as f32, 0.0, 0.0, 0.0],
                        });
                        flat += FLAT_PIXELS as usize;
                    }
                    self.outputs.push((outputs, PIXELS));
                    outputs += PIXELS;
                }
                Device::Linear {
                    pixels,
                    samples,
                    field_of_view,
                    vertical_field_of_view,
                    ..
                } => {
                    let width = field_of_view / *pixels as f64;
                    self.views.push(GpuView {
                        a: [instance, robot, 1, outputs as u32],
                        b: [*pixels, *samples, 0, 0],
                        c: [0; 4],
                        eye,
                        geo: [
                            (field_of_view / 2.0) as f32,
                            width as f32,
                            (vertical_field_of_view / 2.0) as f32,
                            0.0,
                        ],
                    });
                    self.outputs.push((outputs, *pixels as usize));
                    outputs += *pixels as usize;
                }
            }
        }
        Ok((flat, outputs))
    }

    fn ensure_batch(&mut self, need: Capacity) -> Result<(), VisionError> {
        if let Some(batch) = &self.batch {
            if batch.capacity.holds(&need) {
                return Ok(());
            }
        }
        let capacity = match &self.batch {
            Some(batch) => batch.capacity.grown(&need),
            None => Capacity {
                instances: 0,
                poses: 0,
                views: 0,
                flat: 0,
                outputs: 0,
            }
            .grown(&need),
        };
        let limit = self.device.limits().max_storage_buffer_binding_size as usize;
        let largest = (capacity.flat * 4)
            .max(capacity.views * std::mem::size_of::<GpuView>())
            .max(capacity.outputs * 4);
        if largest > limit {
            return Err(VisionError::Device(format!(
                "a batch needs a {largest}-byte buffer and the adapter allows {limit}: split it"
            )));
        }
        let storage = |label: &str, bytes: usize, extra: wgpu::BufferUsages| {
            self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: bytes.max(16) as u64,
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST | extra,
                mapped_at_creation: false,
            })
        };
        let instances = storage(
            "instances",
            capacity.instances * 16,
            wgpu::BufferUsages::empty(),
        );
        let poses = storage("poses", capacity.poses * 16, wgpu::BufferUsages::empty());
        let views = storage(
            "views",
            capacity.views * std::mem::size_of::<GpuView>(),
            wgpu::BufferUsages::empty(),
        );
        let flat = storage("flat", capacity.flat * 4, wgpu::BufferUsages::empty());
        let outputs = storage(
            "outputs",
            capacity.outputs * 4,
            wgpu::BufferUsages::COPY_SRC,
        );
        let uniform = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("batch"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("read back"),
            size: (capacity.outputs * 4).max(16) as u64,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("batch"),
            layout: &self.batch_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: instances.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: poses.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: views.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: flat.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: outputs.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 5,
                    resource: uniform.as_entire_binding(),
                },
            ],
        });
        self.batch = Some(Batch {
            capacity,
            instances,
            poses,
            views,
            uniform,
            outputs,
            staging,
            group,
        });
        Ok(())
    }
}

impl VisionBackend for GpuVision {
    fn describe(&self) -> String {
        format!("wgpu: {}", self.adapter())
    }

    fn render(
        &mut self,
        instances: &[WorldInstance],
        requests: &[VisionRequest],
        out: &mut Vec<Vec<f64>>,
    ) -> Result<(), VisionError> {
        out.resize_with(requests.len(), Vec::new);
        if requests.is_empty() {
            return Ok(());
        }
        let (flat, outputs) = self.plan_batch(instances, requests)?;
        self.ensure_batch(Capacity {
            instances: self.instances.len(),
            poses: self.poses.len(),
            views: self.views.len(),
            flat,
            outputs,
        })?;
        let batch = self.batch.as_ref().expect("ensured above");
        let view_count = self.views.len() as u32;
        self.queue
            .write_buffer(&batch.instances, 0, bytemuck::cast_slice(&self.instances));
        if !self.poses.is_empty() {
            self.queue
                .write_buffer(&batch.poses, 0, bytemuck::cast_slice(&self.poses));
        }
        self.queue
            .write_buffer(&batch.views, 0, bytemuck::cast_slice(&self.views));
        self.queue.write_buffer(
            &batch.uniform,
            0,
            bytemuck::cast_slice(&[view_count, self.warp_table, 0, 0]),
        );
        let widest = self.views.iter().map(|v| v.b[0]).max().unwrap_or(0);
        let (rows, layers) = (view_count.min(ROW), view_count.div_ceil(ROW));
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("vision"),
            });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("trace"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &self.scene_group, &[]);
            pass.set_bind_group(1, &batch.group, &[]);
            pass.set_pipeline(&self.trace);
            pass.dispatch_workgroups(widest.div_ceil(WORKGROUP), rows, layers);
            if flat > 0 {
                pass.set_pipeline(&self.warp);
                pass.dispatch_workgroups((FLAT_COLUMNS as u32).div_ceil(WORKGROUP), rows, layers);
            }
        }
        let bytes = (outputs * 4) as u64;
        encoder.copy_buffer_to_buffer(&batch.outputs, 0, &batch.staging, 0, bytes);
        self.queue.submit([encoder.finish()]);
        let values = read_back(&self.device, &batch.staging, bytes)?;
        for ((start, len), luminance) in self.outputs.iter().zip(out.iter_mut()) {
            luminance.clear();
            luminance.extend(values[*start..start + len].iter().map(|&v| v as f64));
        }
        Ok(())
    }
}

/// Maps `buffer` (a MAP_READ staging buffer) and copies its first `bytes` out as f32.
fn read_back(
    device: &wgpu::Device,
    buffer: &wgpu::Buffer,
    bytes: u64,
) -> Result<Vec<f32>, VisionError> {
    let slice = buffer.slice(..bytes);
    let (sender, receiver) = mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        let _ = sender.send(result);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| VisionError::Device(e.to_string()))?;
    receiver
        .recv()
        .map_err(|e| VisionError::Device(e.to_string()))?
        .map_err(|e| VisionError::Device(e.to_string()))?;
    let values = {
        let data = slice
            .get_mapped_range()
            .map_err(|e| VisionError::Device(e.to_string()))?;
        bytemuck::cast_slice::<u8, f32>(&data).to_vec()
    };
    buffer.unmap();
    Ok(values)
}

async fn open_device() -> Result<(wgpu::Device, wgpu::Queue, wgpu::AdapterInfo), GpuError> {
    // Vulkan, Metal or DX12 first; GL only when none of them has an adapter (or when
    // WGPU_BACKEND asks for it).
    let mut last_error = String::from("no backend tried");
    for backends in [wgpu::Backends::PRIMARY, wgpu::Backends::GL] {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle();
        descriptor.backends = backends;
        let descriptor = descriptor.with_env();
        let instance = wgpu::Instance::new(descriptor);
        let adapter = match instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                force_fallback_adapter: false,
                compatible_surface: None,
                apply_limit_buckets: false,
            })
            .await
        {
            Ok(adapter) => adapter,
            Err(error) => {
                last_error = error.to_string();
                continue;
            }
        };
        let info = adapter.get_info();
        let limits = adapter.limits();
        if limits.max_storage_buffers_per_shader_stage < STORAGE_BUFFERS {
            return Err(GpuError::Device {
                adapter: info.name.clone(),
                why: format!(
                    "it allows {} storage buffers per shader stage and the retina shader needs {STORAGE_BUFFERS}",
                    limits.max_storage_buffers_per_shader_stage
                ),
            });
        }
        let (device, queue) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("regatta"),
                required_limits: limits,
                ..Default::default()
            })
            .await
            .map_err(|e| GpuError::Device {
                adapter: info.name.clone(),
                why: e.to_string(),
            })?;
        return Ok((device, queue, info));
    }
    Err(GpuError::NoAdapter(last_error))
}
