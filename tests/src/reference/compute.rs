//! What the hand-written compute references share: run one shader's `main` entry over a
//! grid of workgroups with its buffers bound in order, and read buffers back.

use sshc_runtime::gpu::Gpu;
use wgpu::util::DeviceExt;

/// One input buffer of [`run`]: a label, its bytes and its usage (`UNIFORM` or `STORAGE`).
pub struct Input<'a> {
    pub label: &'a str,
    pub bytes: &'a [u8],
    pub usage: wgpu::BufferUsages,
}

/// Run `shader`'s `main` compute entry once over `groups` workgroups (x, y), with `inputs`
/// bound at bindings 0.. of group 0 and then one read-write storage buffer per entry of
/// `outputs` (its size in bytes); the outputs read back, in order. Call it inside
/// `Gpu::scoped` so that validation errors come back as values.
pub fn run(gpu: &Gpu, label: &str, shader: &str, inputs: &[Input], outputs: &[u64], groups: (u32, u32)) -> Result<Vec<Vec<u8>>, String> {
    let device = &gpu.device;
    let mut buffers: Vec<wgpu::Buffer> = inputs
        .iter()
        .map(|i| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(i.label),
                contents: i.bytes,
                usage: i.usage,
            })
        })
        .collect();
    for (k, &size) in outputs.iter().enumerate() {
        buffers.push(device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{label} output {k}")),
            size,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        }));
    }
    let total: u64 = outputs.iter().sum();
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(&format!("{label} read-back")),
        size: total,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(shader.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let layout = pipeline.get_bind_group_layout(0);
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(label),
        layout: &layout,
        entries: &buffers
            .iter()
            .enumerate()
            .map(|(i, b)| wgpu::BindGroupEntry {
                binding: i as u32,
                resource: b.as_entire_binding(),
            })
            .collect::<Vec<_>>(),
    });
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(label),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.dispatch_workgroups(groups.0, groups.1, 1);
    }
    let mut at = 0;
    for (k, &size) in outputs.iter().enumerate() {
        encoder.copy_buffer_to_buffer(&buffers[inputs.len() + k], 0, &readback, at, size);
        at += size;
    }
    gpu.queue.submit([encoder.finish()]);
    let raw = map_read(gpu, &readback)?;
    let mut out = Vec::new();
    let mut rest = raw.as_slice();
    for &size in outputs {
        let (a, b) = rest.split_at(size as usize);
        out.push(a.to_vec());
        rest = b;
    }
    Ok(out)
}

/// Map `buffer` (MAP_READ) and copy its bytes out.
pub fn map_read(gpu: &Gpu, buffer: &wgpu::Buffer) -> Result<Vec<u8>, String> {
    let slice = buffer.slice(..);
    let (tx, rx) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = tx.send(r);
    });
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| format!("waiting for the GPU: {e}"))?;
    rx.recv()
        .map_err(|e| format!("reading back: {e}"))?
        .map_err(|e| format!("reading back: {e}"))?;
    let data = slice.get_mapped_range().map_err(|e| format!("reading back: {e}"))?.to_vec();
    buffer.unmap();
    Ok(data)
}
