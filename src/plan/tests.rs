//! The planner: what it chooses, and proof on what is *recorded* (pipelines and
//! their specialization constants), not on timings, that unasked effects cost nothing.

use std::path::{Path, PathBuf};

use crate::host::plan::execute;
use crate::pass::spec;
use crate::plan::{load_geometry, plan, PassKind, Route, SceneFile, Stage};
use crate::testing::{assert_no_validation_messages, validated_context};
use ash::vk;

fn examples() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes")
}

fn scene_file(text: &str) -> SceneFile {
    SceneFile::parse(text, &examples().join("test.toml")).unwrap()
}

fn error(text: &str) -> String {
    SceneFile::parse(text, Path::new("/x/bad.toml"))
        .unwrap_err()
        .to_string()
}

/// The recorded constants of a pipeline kind's stage.
fn constant(
    recorded: &crate::host::plan::Recorded,
    kind: PassKind,
    stage: vk::ShaderStageFlags,
    id: crate::gpu::SpecId,
) -> Option<u32> {
    recorded
        .pipelines
        .iter()
        .filter(|p| p.kind == kind)
        .flat_map(|p| p.constants.iter())
        .find(|(s, _)| *s == stage)
        .and_then(|(_, c)| c.get(id))
}

fn run(file: &SceneFile) -> (crate::plan::Plan, crate::host::plan::Recorded) {
    let ctx = validated_context();
    let scene = load_geometry(file).unwrap();
    let p = plan(file, &scene).unwrap();
    let mut frames = 0;
    let recorded = execute(ctx, &p, &scene, 0..1, &mut |f| {
        assert!(f.rendered.color.is_some() || f.rendered.ids.is_some());
        frames += 1;
        Ok(())
    })
    .unwrap();
    assert_eq!(frames, 1);
    assert_no_validation_messages(ctx);
    (p, recorded)
}

#[test]
fn a_pinhole_scene_records_no_warp_and_no_lens_work() {
    let file = SceneFile::load(&examples().join("pinhole.toml")).unwrap();
    let (p, recorded) = run(&file);
    assert_eq!(p.route, Route::Pinhole);
    assert!(recorded.has(PassKind::PinholeRender));
    assert!(!recorded.has(PassKind::Warp), "{:?}", recorded.pipelines);
    assert!(!recorded.has(PassKind::VertexRender));
}

#[test]
fn k1_k2_runs_shaders_with_the_other_terms_compiled_out() {
    // Alg. 1 (fine enough mesh is cheap here) — its vertex stage has only the radial group.
    let file = SceneFile::load(&examples().join("distortion.toml")).unwrap();
    let (p, recorded) = run(&file);
    assert!(matches!(p.route, Route::Vertex { .. }), "{:?}", p.route);
    let v = vk::ShaderStageFlags::VERTEX;
    let kind = PassKind::VertexRender;
    assert_eq!(
        constant(&recorded, kind, v, spec::RADIAL),
        Some(1),
        "radial on"
    );
    for (id, group) in [
        (spec::RATIONAL, "rational"),
        (spec::TANGENTIAL, "tangential"),
        (spec::PRISM, "prism"),
        (spec::TILT, "tilt"),
    ] {
        assert_eq!(
            constant(&recorded, kind, v, id),
            Some(0),
            "{group} compiled out"
        );
    }
    assert!(!recorded.has(PassKind::Warp));
    assert!(p.expected_error_px <= p.budget_px);
}

#[test]
fn without_chromatic_aberration_the_warp_is_the_single_fetch_variant() {
    // A fine mesh (524k triangles) makes the warp cheaper than Alg. 1 by the planner's tables.
    let text = |chromatic: bool| {
        format!(
            "[geometry]\nscene = \"grid:512\"\n[optics]\ncamera = \"../cameras/barrel_k1k2.json\"\n\
             [effects]\nchromatic_aberration = {chromatic}\nchromatic_scales = [1.003, 1.0, 0.997]\n"
        )
    };
    let c = vk::ShaderStageFlags::COMPUTE;
    let (p, recorded) = run(&scene_file(&text(false)));
    assert!(
        matches!(
            p.route,
            Route::Warp {
                chromatic: None,
                ..
            }
        ),
        "{:?}",
        p.route
    );
    assert_eq!(
        constant(&recorded, PassKind::Warp, c, spec::CHROMATIC),
        Some(0),
        "single fetch"
    );
    assert_eq!(
        constant(&recorded, PassKind::Warp, c, spec::RATIONAL),
        Some(0),
        "rational compiled out"
    );
    let (p, recorded) = run(&scene_file(&text(true)));
    assert!(
        matches!(
            p.route,
            Route::Warp {
                chromatic: Some(_),
                ..
            }
        ),
        "{:?}",
        p.route
    );
    assert_eq!(
        constant(&recorded, PassKind::Warp, c, spec::CHROMATIC),
        Some(1),
        "three fetches"
    );
}

#[test]
fn ids_and_flow_force_the_geometry_path_and_the_budget_sets_the_tessellation() {
    let file = SceneFile::load(&examples().join("ids_and_flow.toml")).unwrap();
    let scene = load_geometry(&file).unwrap();
    let p = plan(&file, &scene).unwrap();
    assert!(matches!(p.route, Route::Vertex { .. }), "{:?}", p.route);
    assert_eq!(p.poses.len(), 3);
    // A tighter budget splits edges further.
    let tight = SceneFile {
        max_error_px: 0.002,
        ..file.clone()
    };
    let q = plan(&tight, &scene).unwrap();
    let edge = |r: &Route| match r {
        Route::Vertex { tessellate } => tessellate.unwrap_or(f64::INFINITY),
        other => panic!("{other:?}"),
    };
    assert!(
        edge(&q.route) < edge(&p.route),
        "{:?} vs {:?}",
        q.route,
        p.route
    );
    assert!(q.expected_error_px <= 0.002);
}

#[test]
fn a_lens_without_depth_of_field_or_vignetting_does_none_of_that_work() {
    let file = SceneFile::load(&examples().join("lens_chromatic.toml")).unwrap();
    let scene = load_geometry(&file).unwrap();
    let p = plan(&file, &scene).unwrap();
    match p.route {
        Route::LensModel {
            samples,
            chromatic,
            vignetting,
            ..
        } => assert_eq!((samples, chromatic, vignetting), (1, true, false)),
        other => panic!("{other:?}"),
    }
    let models = &p.lens().unwrap().models;
    assert_eq!(models.len(), 3, "one model per channel");
    assert!(models.iter().all(|(m, _)| m.samples.len() == 1));
    let file = SceneFile::load(&examples().join("lens_depth_of_field.toml")).unwrap();
    let p = plan(&file, &scene).unwrap();
    let models = &p.lens().unwrap().models;
    assert_eq!(
        models.len(),
        1,
        "one wavelength without chromatic aberration"
    );
    assert_eq!(models[0].0.samples.len(), 10);
}

#[test]
fn scene_file_errors_name_the_file_the_key_and_what_was_expected() {
    let base = "[geometry]\nscene = \"boxes\"\n[optics]\ncamera = \"c.json\"\n";
    let cases = [
        (
            format!("{base}[effects]\nvignette = true\n"),
            "[effects] vignette: unknown key",
        ),
        (
            format!("{base}[effects]\ndistortion = \"yes\"\n"),
            "[effects] distortion: expected true or false",
        ),
        (
            format!("{base}[accuracy]\nmax_error_px = -1\n"),
            "[accuracy] max_error_px: expected pixels > 0",
        ),
        (format!("{base}[optics]\n"), "not valid TOML"),
        (
            "[geometry]\nscene = \"boxes\"\n".to_string(),
            "[optics]: missing",
        ),
        (
            format!("{base}[outputs]\ncolor = false\n"),
            "every output is off",
        ),
        (
            format!("{base}[effects]\nchromatic_aberration = true\n"),
            "[effects] chromatic_scales: missing",
        ),
        (
            format!("{base}[[poses]]\nrvec = [0, 0]\ntvec = [0, 0, 1]\n"),
            "[[poses]] #1.rvec: expected 3 numbers",
        ),
        (
            format!("{base}[render]\nsupersample = 0\n"),
            "[render] supersample: expected a whole number 1..=8, found 0",
        ),
        (
            format!("{base}[render]\njitter = 2.5\n"),
            "[render] jitter: expected a whole number 1..=64, found 2.5",
        ),
        (
            format!("{base}[sensor]\nrolling_shutter = \"diagonal\"\n"),
            "[sensor] rolling_shutter: unknown rolling-shutter readout \"diagonal\"; expected one of top_to_bottom, bottom_to_top, left_to_right, right_to_left",
        ),
        (
            format!("{base}[sensor]\nrolling_shutter = 1\n"),
            "[sensor] rolling_shutter: expected a string",
        ),
        (
            format!("{base}[sensor]\nreadout_ms = 30\n"),
            "[sensor] readout_ms: unknown key; expected one of rolling_shutter",
        ),
        (
            format!("{base}[[poses]]\nrvec = [0, 0, 0]\ntvec = [0, 0, 1]\nend_rvec = [0, 0.1, 0]\n"),
            "[[poses]] #1.end_tvec: missing beside end_rvec",
        ),
        (
            format!("{base}[[poses]]\nrvec = [0, 0, 0]\ntvec = [0, 0, 1]\nend_tvec = [0, 0, 1]\n"),
            "[[poses]] #1.end_rvec: missing beside end_tvec",
        ),
        (
            format!("{base}[[poses]]\nrvec = [0, 0, 0]\ntvec = [0, 0, 1]\nend_rvec = [0, 0, 0]\nend_tvec = [nan, 0, 1]\n"),
            "[[poses]] #1.end_tvec: expected a finite number, found NaN",
        ),
        (
            format!("{base}[[poses]]\nrvec = [0, 0, 0]\ntvec = [0, 0, 1]\nend_pose = [0, 0, 0]\n"),
            "[[poses]] #1.end_pose: unknown key; expected rvec, tvec, end_rvec, end_tvec",
        ),
        (
            format!("{base}[render]\nantialias = 4\n"),
            "[render] antialias: unknown key; expected one of background, supersample, jitter",
        ),
    ];
    for (text, expected) in cases {
        let e = error(&text);
        assert!(e.starts_with("/x/bad.toml: "), "{e}");
        assert!(e.contains(expected), "{e}\n  expected {expected:?}");
    }
    // Planning errors name the key too: vignetting needs a lens.
    let file = scene_file(
        "[geometry]\nscene = \"boxes\"\n[optics]\ncamera = \"../cameras/barrel_k1k2.json\"\n[effects]\nvignetting = true\n",
    );
    let scene = load_geometry(&file).unwrap();
    let e = plan(&file, &scene).unwrap_err().to_string();
    assert!(e.contains("[effects] vignetting"), "{e}");
}

#[test]
fn a_plan_records_into_the_callers_command_buffer_with_timestamps_per_pass() {
    use crate::gpu::QueryPool;
    use crate::plan::record::PlanRecorder;
    let ctx = validated_context();
    let file = SceneFile::load(&examples().join("ids_and_flow.toml")).unwrap();
    let scene = load_geometry(&file).unwrap();
    let p = plan(&file, &scene).unwrap();
    // The headless execution of frame 1 …
    let mut expected = None;
    execute(ctx, &p, &scene, 1..2, &mut |f| {
        expected = Some(f.rendered);
        Ok(())
    })
    .unwrap();
    let expected = expected.unwrap();
    // … equals the same frame recorded by the caller (here the context's command buffer
    // stands for an engine's), IDs exactly.
    let mut recorder = PlanRecorder::new(ctx.gpu(), &p, &scene).unwrap();
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { recorder.prepare(1) }.unwrap();
    let queries = QueryPool::timestamps(ctx.gpu(), recorder.timestamp_count()).unwrap();
    let (_, targets) = recorder.images();
    let targets = targets.unwrap();
    // The caller reads the targets back itself, from the layout `record` documents.
    let readback = crate::host::geometry::TargetsReadback::new(ctx.gpu(), targets).unwrap();
    ctx.submit(|cmd| unsafe {
        recorder.record_setup(cmd);
        recorder.record(cmd, Some(&queries));
        readback.record(
            ctx.gpu(),
            cmd,
            targets,
            ash::vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        )
    })
    .unwrap();
    let got = readback.read().unwrap();
    assert_eq!(got.ids, expected.ids, "IDs differ");
    assert_eq!(got.width, expected.width);
    // The headless path times each pass of the same recorder on its first frame.
    let times = execute(ctx, &p, &scene, 0..1, &mut |_| Ok(()))
        .unwrap()
        .pass_ms;
    assert_eq!(times.len(), 1);
    assert_eq!(times[0].0, "Alg. 1 (vertex + discard)");
    assert!(times[0].1 > 0.0);
    assert_no_validation_messages(ctx);
}

#[test]
fn the_warp_routes_depth_records_into_the_callers_command_buffer_too() {
    // Chromatic colour takes the warp; depth asked beside it goes through the same warp as a
    // second, nearest one (+inf where there is no source). An engine recording the plan gets
    // the very depth the headless execution writes.
    use crate::gpu::{record_compute_download, Buffer};
    let ctx = validated_context();
    let gpu = ctx.gpu();
    let text = std::fs::read_to_string(examples().join("chromatic.toml")).unwrap()
        + "\n[outputs]\ncolor = true\ndepth = true\n";
    let file = scene_file(&text);
    let scene = load_geometry(&file).unwrap();
    let p = plan(&file, &scene).unwrap();
    assert!(matches!(p.route, Route::Warp { .. }), "{:?}", p.route);
    let mut expected = None;
    execute(ctx, &p, &scene, 0..1, &mut |f| {
        expected = Some(f.rendered);
        Ok(())
    })
    .unwrap();
    let expected = expected.unwrap().depth.expect("execute() writes depth");
    let mut recorder = crate::plan::record::PlanRecorder::new(gpu, &p, &scene).unwrap();
    // SAFETY: no submission using it is pending (`submit` waits on its fence).
    unsafe { recorder.prepare(0) }.unwrap();
    let image = recorder
        .warped_depth()
        .expect("the warp route records depth");
    let n = (image.extent.width * image.extent.height) as usize;
    assert_eq!(n, expected.len());
    let download = Buffer::new(
        gpu,
        "test.depth",
        4 * n as u64,
        vk::BufferUsageFlags::TRANSFER_DST,
        gpu_allocator::MemoryLocation::GpuToCpu,
    )
    .unwrap();
    ctx.submit(|cmd| {
        unsafe {
            recorder.record_setup(cmd);
            recorder.record(cmd, None);
            record_compute_download(gpu, cmd, image, &download);
        }
        Ok(())
    })
    .unwrap();
    let got = download.read_pod::<f32>(n).unwrap();
    let bits = |v: &[f32]| v.iter().map(|z| z.to_bits()).collect::<Vec<_>>();
    assert!(
        bits(&got) == bits(&expected),
        "depth differs from execute()'s"
    );
    let surface = got.iter().filter(|z| z.is_finite()).count();
    assert!(
        surface > n / 2,
        "the grid should fill most of the frame ({surface} of {n})"
    );
    assert!(got.iter().all(|&z| z.is_infinite() || z > 0.0));
    assert_no_validation_messages(ctx);
}

#[test]
fn render_keys_anti_alias_the_colour_and_leave_the_data_at_one_sample() {
    // [render] supersample and jitter: the plan says so, execute() averages the colour, and
    // IDs, flow and depth are the very same single-sample images as without them.
    let ctx = validated_context();
    let base = std::fs::read_to_string(examples().join("ids_and_flow.toml")).unwrap();
    let plain = scene_file(&base);
    let smooth = scene_file(&format!("{base}\n[render]\nsupersample = 2\njitter = 2\n"));
    assert_eq!(smooth.antialias.supersample, 2);
    let scene = load_geometry(&plain).unwrap();
    let frame = |file: &SceneFile| {
        let p = plan(file, &scene).unwrap();
        let mut out = None;
        execute(ctx, &p, &scene, 0..1, &mut |f| {
            out = Some(f.rendered);
            Ok(())
        })
        .unwrap();
        (p, out.unwrap())
    };
    let (p1, one) = frame(&plain);
    let (p4, four) = frame(&smooth);
    assert!(!p1.steps.iter().any(|s| s.stage == Stage::Antialias));
    let step = p4
        .steps
        .iter()
        .find(|s| s.stage == Stage::Antialias)
        .expect("an AA step");
    assert!(
        step.why.contains("2× supersampling and 2 jittered"),
        "{}",
        step.why
    );
    assert_eq!(
        p1.route, p4.route,
        "anti-aliasing does not change the route"
    );
    // Bit for bit (flow and depth hold NaN and +inf where nothing was drawn).
    let bits = |v: Option<Vec<f32>>| v.map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>());
    let flow_bits =
        |v: &Option<Vec<[f32; 2]>>| bits(v.as_ref().map(|v| v.iter().flatten().copied().collect()));
    assert!(
        one.ids == four.ids,
        "IDs are one sample per pixel either way"
    );
    assert!(
        bits(one.depth.clone()) == bits(four.depth.clone()),
        "depth differs"
    );
    assert!(
        flow_bits(&one.flow) == flow_bits(&four.flow),
        "flow differs"
    );
    let (a, b) = (one.color.unwrap(), four.color.unwrap());
    let diffs: Vec<f32> = (0..a.len())
        .map(|i| {
            let (p, q) = (a.rgba_f32(i), b.rgba_f32(i));
            (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, f32::max)
        })
        .collect();
    let changed = diffs.iter().filter(|&&d| d > 2.0 / 255.0).count();
    let mean = diffs.iter().sum::<f32>() / diffs.len() as f32;
    // Edges and fine texture change, the picture does not: many pixels move a little.
    eprintln!(
        "anti-aliasing: {changed} of {} pixels changed, mean {mean}",
        diffs.len()
    );
    assert!(changed > 0, "anti-aliasing changed no pixel");
    assert!(mean < 0.05, "mean change {mean}");
    // The engine recorder draws one sample per pixel and says so rather than ignore the keys.
    let e = match crate::plan::record::PlanRecorder::new(ctx.gpu(), &p4, &scene) {
        Ok(_) => panic!("the recorder accepted an anti-aliased plan"),
        Err(e) => e.to_string(),
    };
    assert!(e.contains("one sample per pixel"), "{e}");
    // A lens scene cannot take the keys.
    let lens = std::fs::read_to_string(examples().join("lens_chromatic.toml")).unwrap();
    let lens = scene_file(&format!("{lens}\n[render]\nsupersample = 2\n"));
    let e = plan(&lens, &load_geometry(&lens).unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("[render] supersample"), "{e}");
    assert_no_validation_messages(ctx);
}

#[test]
fn a_scene_of_many_frames_warps_through_a_map_built_once() {
    // Six chromatic frames at 0.01 px on a k1 k2 lens: a coarse cubic map (5e-4 px) built
    // once beats solving fixed-point per pixel every frame, and --explain names both.
    let text =
        "[geometry]\nscene = \"grid:16\"\n[optics]\ncamera = \"../cameras/barrel_k1k2.json\"\n\
        [effects]\nchromatic_aberration = true\nchromatic_scales = [1.004, 1.0, 0.996]\n\
        [accuracy]\nmax_error_px = 0.01\n[pose_sequence]\n\
        from = { rvec = [0.0, 0.0, 0.0], tvec = [0.0, 0.0, 3.0] }\n\
        to = { rvec = [0.1, 0.2, 0.0], tvec = [0.2, 0.0, 3.0] }\nframes = 6\n";
    let file = scene_file(text);
    let scene = load_geometry(&file).unwrap();
    let p = plan(&file, &scene).unwrap();
    assert!(
        matches!(p.route, Route::Warp { map: true, .. }),
        "{:?}",
        p.route
    );
    let why = &p
        .steps
        .iter()
        .find(|s| matches!(s.stage, Stage::Warp { chromatic: true }))
        .unwrap()
        .why;
    assert!(
        why.contains("per pixel") && why.contains("precomputed map"),
        "{why}"
    );
    assert!(p.expected_error_px <= p.budget_px);
    // The same frame solved per pixel (Newton) agrees with the map's within the map's error.
    let ctx = validated_context();
    let frame = |p: &crate::plan::Plan| {
        let mut out = None;
        let recorded = execute(ctx, p, &scene, 2..3, &mut |f| {
            out = Some(f.rendered.color.unwrap());
            Ok(())
        })
        .unwrap();
        (out.unwrap(), recorded)
    };
    let (mapped, recorded) = frame(&p);
    let c = vk::ShaderStageFlags::COMPUTE;
    assert_eq!(
        constant(&recorded, PassKind::Warp, c, spec::USE_MAP),
        Some(1)
    );
    let mut solved_plan = p.clone();
    solved_plan.route = Route::Warp {
        method: crate::InverseMethod::Newton,
        chromatic: Some([1.004, 1.0, 0.996]),
        map: false,
    };
    let (solved, recorded) = frame(&solved_plan);
    assert_eq!(
        constant(&recorded, PassKind::Warp, c, spec::USE_MAP),
        Some(0)
    );
    let differ = (0..mapped.len())
        .filter(|&i| {
            let (a, b) = (mapped.rgba_f32(i), solved.rgba_f32(i));
            (0..4).any(|k| (a[k] - b[k]).abs() > 2.0 / 255.0)
        })
        .count();
    assert!(
        differ * 1000 < mapped.len(),
        "{differ} of {} pixels differ by more than 2 grey levels",
        mapped.len()
    );
    assert_no_validation_messages(ctx);
}

#[test]
fn a_lens_past_a_pinholes_reach_is_planned_on_the_cheaper_of_alg1_and_the_cube_map() {
    let dir = std::env::temp_dir().join(format!("vklens-plan-fisheye-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("fish.json"),
        r#"{"model": "opencv_fisheye", "width": 480, "height": 480, "fx": 138, "fy": 138, "cx": 239.5, "cy": 239.5, "dist_coeffs": [0.02, -0.004, 0.0005, 0], "max_fov_deg": 200}"#,
    )
    .unwrap();
    let text = "[geometry]\nscene = \"room\"\n[optics]\ncamera = \"fish.json\"\n[accuracy]\nmax_error_px = 0.5\n";
    let parse = |t: &str| SceneFile::parse(t, &dir.join("scene.toml")).unwrap();
    let file = parse(text);
    let scene = load_geometry(&file).unwrap();
    // Colour alone: both can render it; Alg. 1 draws the 12,288 triangles once, the cube map
    // six times and warps every pixel, so Alg. 1 is estimated cheaper, and says so.
    let p = plan(&file, &scene).unwrap();
    assert!(matches!(p.route, Route::Vertex { .. }), "{:?}", p.route);
    let why: Vec<&str> = p.steps.iter().map(|s| s.why.as_str()).collect();
    assert!(
        why.iter().any(|w| w.contains("no pinhole warp")
            && w.contains("90°")
            && w.contains("for a cube map")),
        "{why:?}"
    );
    assert!(
        why.iter()
            .any(|w| w.contains("compiled in: opencv_fisheye")),
        "{why:?}"
    );

    // Chromatic aberration: Alg. 1 cannot give each channel its own lens and no pinhole
    // source holds the lens, so the cube map renders it, on the GPU, each channel through its
    // own rays; what the planner records is what `render --path cube` draws.
    let chromatic = format!(
        "{text}[effects]\nchromatic_aberration = true\nchromatic_scales = [1.002, 1.0, 0.998]\n"
    );
    let file = parse(&chromatic);
    let p = plan(&file, &scene).unwrap();
    let Route::Cube {
        side,
        chromatic: Some(scales),
    } = p.route
    else {
        panic!("not the cube route: {:?}", p.route);
    };
    assert_eq!(
        side, 276,
        "one face pixel per output pixel at the centre: 2 fx"
    );
    assert_eq!(scales, [1.002, 1.0, 0.998]);
    assert_eq!(
        p.steps.iter().map(|s| s.stage).collect::<Vec<_>>(),
        [Stage::CubeFaces, Stage::SphereWarp { chromatic: true }]
    );
    assert!(
        p.steps[0].why.contains("no pinhole warp"),
        "{}",
        p.steps[0].why
    );
    let ctx = validated_context();
    let mut planned = None;
    let recorded = execute(ctx, &p, &scene, 0..1, &mut |f| {
        planned = f.rendered.color;
        Ok(())
    })
    .unwrap();
    assert!(recorded.has(PassKind::SphereWarp));
    assert_eq!(
        constant(
            &recorded,
            PassKind::SphereWarp,
            vk::ShaderStageFlags::COMPUTE,
            spec::CHROMATIC
        ),
        Some(1)
    );
    let planned = planned.expect("the cube route renders colour");
    let camera = p.camera().cloned().unwrap();
    let mut request =
        crate::plan::RenderRequest::color(&camera, crate::plan::PathChoice::Cube { side });
    request.pose = p.poses[0];
    request.chromatic = Some(scales);
    let flag = crate::host::plan::render_request(ctx, &scene, &request, &mut |_| {})
        .unwrap()
        .color
        .unwrap();
    assert!(
        planned.pixels == flag.pixels,
        "the plan and render --path cube differ"
    );
    let lit = (0..planned.len())
        .filter(|&i| planned.rgba_f32(i)[3] > 0.5)
        .count();
    assert!(lit * 2 > planned.len(), "the room fills the image circle");
    // Supersampled, the faces are as fine as the larger camera's pixels.
    let file = parse(&format!("{chromatic}[render]\nsupersample = 2\n"));
    let p2 = plan(&file, &scene).unwrap();
    execute(ctx, &p2, &scene, 0..1, &mut |f| {
        let c = f.rendered.color.expect("colour");
        assert_eq!((c.width, c.height), (480, 480));
        Ok(())
    })
    .unwrap();
    assert_no_validation_messages(ctx);

    // A cube map carries colour alone: chromatic aberration with IDs cannot be planned.
    let with_ids = format!("{chromatic}[outputs]\nids = true\n");
    let file = parse(&with_ids);
    let e = plan(&file, &scene).unwrap_err().to_string();
    assert!(
        e.contains("chromatic_aberration") && e.contains("cube map") && e.contains("colour alone"),
        "{e}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A model of the table beyond OpenCV's (the double sphere example, 195°): planned on the
/// vertex path for its IDs and depth, its shaders specialized for that model alone.
#[test]
fn a_double_sphere_scene_runs_alg1_specialized_for_its_model() {
    let file = SceneFile::load(&examples().join("double_sphere.toml")).unwrap();
    let (p, recorded) = run(&file);
    assert!(matches!(p.route, Route::Vertex { .. }), "{:?}", p.route);
    assert!(recorded.has(PassKind::VertexRender));
    let model = crate::model::ModelKind::DoubleSphere.gpu_id();
    let got = constant(
        &recorded,
        PassKind::VertexRender,
        vk::ShaderStageFlags::VERTEX,
        spec::MODEL,
    );
    assert_eq!(got, Some(model), "{:?}", recorded.pipelines);
    let why: Vec<&str> = p.steps.iter().map(|s| s.why.as_str()).collect();
    assert!(
        why.iter().any(|w| w.contains("compiled in: double_sphere")),
        "{why:?}"
    );
}

/// A scene file at `at` of two frames through `camera` (relative to `at`), the second moving
/// during its readout unless `still`, with `extra` tables.
fn two_frames_at(at: &Path, camera: &str, still: bool, extra: &str) -> SceneFile {
    let end = if still {
        "[0.0, 0.0, 0.0]"
    } else {
        "[0.0, 0.05, 0.0]"
    };
    let text = format!(
        "[geometry]\nscene = \"boxes\"\n[optics]\ncamera = \"{camera}\"\n[effects]\ndistortion = false\n\
         [[poses]]\nrvec = [0.0, 0.0, 0.0]\ntvec = [0.0, 0.0, 4.0]\n\
         [[poses]]\nrvec = [0.0, 0.0, 0.0]\ntvec = [0.0, 0.0, 4.0]\nend_rvec = {end}\nend_tvec = [0.0, 0.0, 4.0]\n{extra}"
    );
    SceneFile::parse(&text, at).unwrap()
}

fn two_frames(camera: &str, still: bool, extra: &str) -> SceneFile {
    two_frames_at(&examples().join("test.toml"), camera, still, extra)
}

#[test]
fn a_rolling_shutter_is_explained_with_its_source_and_a_moving_one_takes_the_vertex_path() {
    let barrel = "../cameras/barrel_k1k2.json";
    let planned = |file: &SceneFile| plan(file, &load_geometry(file).unwrap());
    let rolling = "[sensor]\nrolling_shutter = \"top_to_bottom\"\n";
    // Still frames: global by default, the readout named where the scene gives one.
    let p = planned(&two_frames(barrel, true, "")).unwrap();
    assert_eq!(p.shutter, crate::plan::Shutter::Global);
    let text = p.explain(None, &[]);
    assert!(
        text.contains("shutter: global: every line is read at once"),
        "{text}"
    );
    let p = planned(&two_frames(barrel, true, rolling)).unwrap();
    let text = p.explain(None, &[]);
    assert!(
        text.contains("shutter: rolling, top_to_bottom, from [sensor] rolling_shutter;")
            && text.contains("the global shutter's, exactly"),
        "{text}"
    );
    // A moving camera through a rolling shutter: drawn per vertex (here without distortion,
    // by the pinhole render's vertex shader), and said so; through a global shutter the end
    // pose contradicts it, and it is refused, never rendered as a global shutter.
    let p = planned(&two_frames(barrel, false, rolling)).unwrap();
    assert_eq!(
        p.shutter.moving_readout(),
        Some(crate::model::rolling_shutter::Readout::TopToBottom)
    );
    assert_eq!(p.end_pose(0), Some(p.poses[0]));
    assert_ne!(p.end_pose(1), Some(p.poses[1]));
    let text = p.explain(None, &[]);
    assert!(
        text.contains("the camera moves during frame 2") && text.contains("exactly per vertex"),
        "{text}"
    );
    let e = planned(&two_frames(barrel, false, "")).unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::Input);
    let e = e.to_string();
    assert!(
        e.contains("[[poses]] #2.end_rvec") && e.contains("the shutter is global"),
        "{e}"
    );
    // A lens prescription states no readout; the scene's key refuses the same way.
    let lens = std::fs::read_to_string(examples().join("lens_chromatic.toml")).unwrap();
    let lens = scene_file(&format!(
        "{lens}\n{rolling}[[poses]]\nrvec = [0, 0, 0]\ntvec = [0, 0, 1]\nend_rvec = [0, 0, 0]\nend_tvec = [0.1, 0, 1]\n"
    ));
    let e = planned(&lens).unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::Unsupported);
    let e = e.to_string();
    assert!(
        e.contains("[sensor] rolling_shutter")
            && e.contains("[[poses]] #1 moves")
            && e.contains("the image-based lens model draws a frame from one pose"),
        "{e}"
    );
}

/// A barrel lens over the grid, ID and depth outputs: frame 1 still, frame 2 panning during
/// its readout (`end` its end pose; `None`: still too), with `extra` tables.
fn moving_grid(end: Option<&str>, extra: &str) -> SceneFile {
    let end = end
        .map(|e| {
            format!(
                "{e}
"
            )
        })
        .unwrap_or_default();
    scene_file(&format!(
        "[geometry]
scene = \"grid:16\"
[optics]
camera = \"../cameras/barrel_k1k2.json\"
         [outputs]
color = true
ids = true
depth = true
         [[poses]]
rvec = [0.0, 0.0, 0.0]
tvec = [0.0, 0.0, 2.0]
         [[poses]]
rvec = [0.0, -0.05, 0.0]
tvec = [0.05, 0.0, 2.0]
{end}{extra}"
    ))
}

#[test]
fn a_moving_rolling_shutter_renders_per_vertex_and_its_still_frames_as_the_global_shutter() {
    let ctx = validated_context();
    let rolling = "[sensor]\nrolling_shutter = \"top_to_bottom\"\n";
    let end = "end_rvec = [0.0, 0.05, 0.0]\nend_tvec = [-0.05, 0.0, 2.0]";
    let moving = moving_grid(Some(end), rolling);
    let global = moving_grid(None, "");
    let scene = load_geometry(&moving).unwrap();
    let p = plan(&moving, &scene).unwrap();
    assert!(matches!(p.route, Route::Vertex { .. }), "{:?}", p.route);
    let text = p.explain(None, &[]);
    assert!(
        text.contains("each vertex is drawn where its own line reads it"),
        "{text}"
    );
    let frames = |p: &crate::plan::Plan| {
        let mut out = Vec::new();
        execute(ctx, p, &scene, 0..2, &mut |f| {
            out.push(f.rendered);
            Ok(())
        })
        .unwrap();
        out
    };
    let (got, twin) = (frames(&p), frames(&plan(&global, &scene).unwrap()));
    let bits = |r: &crate::imaging::Rendered| {
        let depth = r.depth.as_ref().unwrap().iter().map(|z| z.to_bits());
        (r.ids.clone().unwrap(), depth.collect::<Vec<_>>())
    };
    // The still frame: the global shutter's, bit for bit (the pass solves nothing where the
    // readout time cannot matter, so the arithmetic is the same).
    assert_eq!(bits(&got[0]), bits(&twin[0]));
    assert_eq!(got[0].color, twin[0].color);
    // The moving one: another picture than any one pose gives.
    let moved = got[1]
        .ids
        .as_ref()
        .unwrap()
        .iter()
        .zip(twin[1].ids.as_ref().unwrap());
    let changed = moved.filter(|(a, b)| a != b).count();
    assert!(changed > 1000, "{changed} pixels change ID under the pan");
    // Chromatic aberration needs the warp, which draws a frame from one pose: in bands of
    // lines, none of which meets the default 0.01 px budget under this pan: refused.
    let chromatic = moving_grid(
        Some(end),
        &format!("{rolling}[effects]\nchromatic_aberration = true\nchromatic_scales = [1.002, 1.0, 0.998]\n"),
    );
    let e = plan(&chromatic, &scene).unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::Input);
    let e = e.to_string();
    assert!(
        e.contains("[sensor] rolling_shutter")
            && e.contains("[accuracy] max_error_px = 0.01")
            && e.contains("chromatic_aberration")
            && e.contains("with 64 bands"),
        "{e}"
    );
    assert_no_validation_messages(ctx);
}

#[test]
fn a_camera_files_readout_is_the_default_and_the_scene_key_overrides_it() {
    // An NCore f-theta camera read left to right, beside its scenes in a scratch folder.
    let dir = std::env::temp_dir().join(format!("vklens-plan-shutter-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(
        dir.join("ncore.json"),
        r#"{"camera_model_type": "ftheta", "camera_model_parameters": {
        "resolution": [640, 480], "principal_point": [319.5, 239.5],
        "reference_poly": "PIXELDIST_TO_ANGLE",
        "pixeldist_to_angle_poly": [0.0, 2.0e-3, 0.0, 0.0, 0.0, 0.0],
        "angle_to_pixeldist_poly": [0.0, 500.0, 0.0, 0.0, 0.0, 0.0],
        "linear_cde": [1.0, 0.0, 0.0], "max_angle": 0.9,
        "shutter_type": "ROLLING_LEFT_TO_RIGHT"}}"#,
    )
    .unwrap();
    let file = |still, extra| two_frames_at(&dir.join("s.toml"), "ncore.json", still, extra);
    let planned = |f: &SceneFile| plan(f, &load_geometry(f).unwrap());
    let p = planned(&file(true, "")).unwrap();
    assert_eq!(
        p.shutter,
        crate::plan::Shutter::Rolling {
            readout: crate::model::rolling_shutter::Readout::LeftToRight,
            from: crate::plan::ReadoutSource::CameraFile,
        }
    );
    let text = p.explain(None, &[]);
    assert!(
        text.contains(
            "rolling, left_to_right, from the camera file's shutter_type ROLLING_LEFT_TO_RIGHT"
        ),
        "{text}"
    );
    let p = planned(&file(
        true,
        "[sensor]\nrolling_shutter = \"bottom_to_top\"\n",
    ))
    .unwrap();
    assert!(
        p.explain(None, &[])
            .contains("rolling, bottom_to_top, from [sensor] rolling_shutter;"),
        "{:?}",
        p.shutter
    );
    // Moving: the camera file's readout is solved per vertex.
    let p = planned(&file(false, "")).unwrap();
    assert_eq!(
        p.shutter,
        crate::plan::Shutter::Moving {
            readout: crate::model::rolling_shutter::Readout::LeftToRight,
            from: crate::plan::ReadoutSource::CameraFile,
            frame: 1,
        }
    );
    let text = p.explain(None, &[]);
    assert!(
        text.contains("shutter_type ROLLING_LEFT_TO_RIGHT")
            && text.contains("moves during frame 2"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_rolling_shutter_example_and_its_global_twin_render_and_differ() {
    let ctx = validated_context();
    let render = |name: &str| {
        let file = SceneFile::load(&examples().join(name)).unwrap();
        let scene = load_geometry(&file).unwrap();
        let p = plan(&file, &scene).unwrap();
        let mut out = None;
        execute(ctx, &p, &scene, 0..1, &mut |f| {
            out = Some(f.rendered);
            Ok(())
        })
        .unwrap();
        (p, out.unwrap())
    };
    let (moving, panned) = render("rolling_shutter.toml");
    let (global, still) = render("rolling_shutter_global.toml");
    assert!(moving.shutter.moving_readout().is_some());
    assert!(matches!(moving.route, Route::Vertex { .. }));
    assert_eq!(global.shutter, crate::plan::Shutter::Global);
    let (a, b) = (panned.ids.unwrap(), still.ids.unwrap());
    let board = b.iter().filter(|&&id| id != 0).count();
    let changed = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    assert!(board > 50_000, "the board fills the frame ({board} px)");
    assert!(
        changed > board / 10,
        "{changed} of {board} px change square"
    );
    assert_no_validation_messages(ctx);
}

#[test]
fn a_moving_rolling_shutter_without_distortion_renders_through_the_pinhole_pass() {
    // Distortion dropped: the pinhole route's vertex shader solves each vertex's readout time.
    let ctx = validated_context();
    let barrel = "../cameras/barrel_k1k2.json";
    let rolling = "[sensor]\nrolling_shutter = \"top_to_bottom\"\n[outputs]\nids = true\n";
    let frames = |file: &SceneFile| {
        let scene = load_geometry(file).unwrap();
        let p = plan(file, &scene).unwrap();
        assert_eq!(p.route, Route::Pinhole);
        let mut out = Vec::new();
        execute(ctx, &p, &scene, 0..2, &mut |f| {
            out.push(f.rendered.ids.unwrap());
            Ok(())
        })
        .unwrap();
        out
    };
    let moving = frames(&two_frames(barrel, false, rolling));
    let still = frames(&two_frames(barrel, true, rolling));
    assert_eq!(moving[0], still[0], "the still first frame is the same");
    assert!(moving[0].iter().any(|&id| id != 0));
    let changed = moving[1]
        .iter()
        .zip(&still[1])
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        changed > 500,
        "{changed} pixels change object under the turn"
    );
    assert_no_validation_messages(ctx);
}

/// The barrel lens over the grid, colour alone, panning during the second frame's top-to-bottom
/// readout (about 3° and 5 cm), with `extra` tables.
fn banded_grid(extra: &str) -> SceneFile {
    scene_file(&format!(
        "[geometry]\nscene = \"grid:16\"\n[optics]\ncamera = \"../cameras/barrel_k1k2.json\"\n\
         [sensor]\nrolling_shutter = \"top_to_bottom\"\n\
         [[poses]]\nrvec = [0.0, 0.0, 0.0]\ntvec = [0.0, 0.0, 2.0]\n\
         [[poses]]\nrvec = [0.0, -0.025, 0.0]\ntvec = [0.025, 0.0, 2.0]\n\
         end_rvec = [0.0, 0.025, 0.0]\nend_tvec = [-0.025, 0.0, 2.0]\n{extra}"
    ))
}

const BANDS_CHROMATIC: &str =
    "[effects]\nchromatic_aberration = true\nchromatic_scales = [1.002, 1.0, 0.998]\n";

/// A 160×120 k1 k2 camera: lavapipe renders a banded frame's source once per band, so the
/// GPU checks of the bands keep their frames small.
fn small_barrel() -> crate::model::Camera {
    crate::model::Camera::from_coeffs(
        160,
        120,
        crate::model::Intrinsics {
            fx: 80.0,
            fy: 80.0,
            cx: 79.5,
            cy: 59.5,
        },
        &[-0.11, 0.02, 0.0, 0.0],
    )
    .unwrap()
}

fn budget(px: f64) -> String {
    format!("[accuracy]\nmax_error_px = {px}\n")
}

#[test]
fn chromatic_aberration_through_a_moving_rolling_shutter_takes_the_fewest_bands_that_meet_the_budget(
) {
    let planned = |px: f64| {
        let file = banded_grid(&format!("{BANDS_CHROMATIC}{}", budget(px)));
        plan(&file, &load_geometry(&file).unwrap())
    };
    let p = planned(0.5).unwrap();
    assert!(
        matches!(
            p.route,
            Route::Warp {
                chromatic: Some(_),
                ..
            }
        ),
        "{:?}",
        p.route
    );
    let k = p.bands.unwrap();
    assert!(
        crate::model::rolling_shutter::bands::BAND_COUNTS.contains(&k),
        "{k}"
    );
    assert!(p.expected_error_px <= 0.5, "{}", p.expected_error_px);
    // The fewest: a budget just under what k bands leave takes more of them, and one twice
    // what they leave takes no more.
    let tighter = planned(p.expected_error_px * 0.99).unwrap();
    assert!(tighter.bands.unwrap() > k, "{:?}", tighter.bands);
    assert!(tighter.expected_error_px < p.expected_error_px);
    let looser = planned(p.expected_error_px * 2.0).unwrap();
    assert!(looser.bands.unwrap() <= k, "{:?}", looser.bands);
    // The cost grows with the bands: a source render each.
    assert!(tighter.estimated_ms > p.estimated_ms);
    // A still camera never takes bands.
    let still = banded_grid(&format!("{BANDS_CHROMATIC}{}", budget(0.5)))
        .poses
        .len();
    assert_eq!(still, 2);
    let file = scene_file(&format!(
        "[geometry]\nscene = \"grid:16\"\n[optics]\ncamera = \"../cameras/barrel_k1k2.json\"\n[sensor]\nrolling_shutter = \"top_to_bottom\"\n{BANDS_CHROMATIC}{}",
        budget(0.5)
    ));
    let p = plan(&file, &load_geometry(&file).unwrap()).unwrap();
    assert_eq!(p.bands, None);
    assert!(matches!(p.route, Route::Warp { .. }));
}

#[test]
fn a_request_through_the_warp_takes_the_bands_the_planner_takes_for_its_scene_file() {
    use crate::plan::{PathChoice, RenderRequest};
    let camera = crate::io::load_camera(&examples().join("../cameras/barrel_k1k2.json")).unwrap();
    for px in [0.5, 2.0, 8.0] {
        let file = banded_grid(&format!("{BANDS_CHROMATIC}{}", budget(px)));
        let scene = load_geometry(&file).unwrap();
        let planned = plan(&file, &scene).unwrap();
        // The frame that moves, as flags give it: the warp named, the same budget.
        let mut request = RenderRequest::color(
            &camera,
            PathChoice::Warp {
                method: crate::model::InverseMethod::Newton,
                density: 1.0,
            },
        );
        request.pose = file.poses[1];
        request.previous_pose = file.poses[1];
        request.rolling_shutter = Some((
            crate::model::rolling_shutter::Readout::TopToBottom,
            file.end_poses[1].unwrap(),
        ));
        request.max_error_px = px;
        let p = crate::plan::Plan::from_request_with_scene(&request, &scene, 16384).unwrap();
        assert!(planned.bands.is_some());
        assert_eq!(p.bands, planned.bands, "{px} px");
        assert!(p.expected_error_px <= px && p.budget_px == px);
        assert_eq!(p.steps[0].stage, Stage::BandRenders);
        let k = p.bands.unwrap();
        assert!(
            p.steps[0]
                .why
                .contains(&format!("{k} bands of lines leave")),
            "{}",
            p.steps[0].why
        );
        // Without the scene the bands cannot be sized: refused as before.
        let e = crate::plan::Plan::from_request(&request, 16384).unwrap_err();
        assert_eq!(e.argument_name(), Some("rolling_shutter"));
        // A budget no count meets: refused, naming it and what 64 bands leave.
        request.max_error_px = 1e-4;
        let e = crate::plan::Plan::from_request_with_scene(&request, &scene, 16384).unwrap_err();
        assert_eq!(e.argument_name(), Some("max_error_px"), "{e}");
        assert!(e.to_string().contains("even 64 bands leave"), "{e}");
    }
}

#[test]
fn bands_no_count_can_meet_are_refused_naming_the_shutter_and_the_budget() {
    let file = banded_grid(&format!("{BANDS_CHROMATIC}{}", budget(0.001)));
    let e = plan(&file, &load_geometry(&file).unwrap()).unwrap_err();
    assert_eq!(e.kind(), crate::ErrorKind::Input);
    let e = e.to_string();
    assert!(
        e.contains("test.toml: [sensor] rolling_shutter, [accuracy] max_error_px = 0.001")
            && e.contains("[[poses]] #2 moves during its top_to_bottom readout")
            && e.contains("with 64 bands")
            && e.contains("chromatic_aberration"),
        "{e}"
    );
    // The error 64 bands would leave, which a budget at it accepts.
    let left: f64 = e
        .split(" px even with 64 bands")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    assert!(left > 0.001 && left < 0.5, "{left}");
    let file = banded_grid(&format!("{BANDS_CHROMATIC}{}", budget(left * 1.01)));
    let p = plan(&file, &load_geometry(&file).unwrap()).unwrap();
    assert_eq!(p.bands, Some(64));
}

#[test]
fn without_chromatic_aberration_a_moving_rolling_shutter_keeps_the_vertex_path() {
    // The exact path costs a render and the per-vertex solve; the fewest bands that meet the
    // budget cost four renders and the warp: the vertex path, and --explain says why.
    let file = banded_grid(&budget(0.5));
    let p = plan(&file, &load_geometry(&file).unwrap()).unwrap();
    assert!(matches!(p.route, Route::Vertex { .. }), "{:?}", p.route);
    assert_eq!(p.bands, None);
    let text = p.explain(None, &[]);
    assert!(
        text.contains("each vertex is drawn where its own line reads it")
            && text.contains("bands of lines, each from its middle line's pose, would leave")
            && text.contains("but cost est."),
        "{text}"
    );
    // At the default budget no count of bands meets it.
    let file = banded_grid("");
    let p = plan(&file, &load_geometry(&file).unwrap()).unwrap();
    assert!(matches!(p.route, Route::Vertex { .. }));
    assert!(
        p.explain(None, &[]).contains("even 64 bands of lines"),
        "{}",
        p.explain(None, &[])
    );
}

#[test]
fn the_bands_are_explained_with_their_count_error_and_budget() {
    let file = banded_grid(&format!("{BANDS_CHROMATIC}{}", budget(0.5)));
    let p = plan(&file, &load_geometry(&file).unwrap()).unwrap();
    let k = p.bands.unwrap();
    let text = p.explain(None, &[]);
    assert!(
        text.contains(&format!("in {k} bands of lines (a moving rolling shutter)")),
        "{text}"
    );
    assert!(
        text.contains("pinhole render per band (overscanned): the camera moves during the readout and the warp draws a frame from one pose: chromatic aberration needs the warp (Alg. 1 cannot give each channel its own lens)")
            && text.contains(&format!("; {k} bands leave {:.2} px ≤ 0.50 px budget", p.expected_error_px))
            && text.contains("from the pose of the band's middle line"),
        "{text}"
    );
    // IDs beside: the warp in bands for colour, the exact vertex path for the IDs.
    let file = banded_grid(&format!(
        "{BANDS_CHROMATIC}{}[outputs]\ncolor = true\nids = true\n",
        budget(0.5)
    ));
    let p = plan(&file, &load_geometry(&file).unwrap()).unwrap();
    assert!(
        matches!(p.route, Route::WarpAndVertex { .. }),
        "{:?}",
        p.route
    );
    assert_eq!(p.bands, Some(k));
    let text = p.explain(None, &[]);
    assert!(
        text.contains("drawn exactly, each vertex where its own line reads it"),
        "{text}"
    );
}

#[test]
fn bands_render_chromatic_colour_and_exact_ids_in_one_frame() {
    let ctx = validated_context();
    let file = banded_grid(&format!(
        "{BANDS_CHROMATIC}{}[outputs]\ncolor = true\nids = true\n",
        budget(0.5)
    ));
    let scene = load_geometry(&file).unwrap();
    let mut p = plan(&file, &scene).unwrap();
    // A small frame: lavapipe renders the source once per band.
    let camera = small_barrel();
    p.optics = crate::plan::Optics::Camera(camera);
    p.background = [0.0, 0.0, 0.0, 1.0];
    let mut out = Vec::new();
    let recorded = execute(ctx, &p, &scene, 0..2, &mut |f| {
        out.push(f.rendered);
        Ok(())
    })
    .unwrap();
    assert!(recorded.has(PassKind::Warp) && recorded.has(PassKind::VertexRender));
    for f in &out {
        // Every pixel written by one band's warp: opaque, drawn or the background.
        let Some(crate::imaging::Pixels::Rgba8(c)) = f.color.as_ref().map(|c| &c.pixels) else {
            panic!("8-bit colour expected");
        };
        assert!(c.iter().all(|p| p[3] == 255));
        assert!(f.ids.as_ref().unwrap().iter().any(|&id| id != 0));
    }
    assert_no_validation_messages(ctx);
}

/// Frame 0 of `plan` rendered once.
fn first_frame(
    ctx: &crate::host::Context,
    plan: &crate::plan::Plan,
    scene: &crate::scene::Scene,
) -> crate::imaging::Rendered {
    let mut out = None;
    crate::host::plan::execute_untimed(ctx, plan, scene, [0], &mut |f| {
        out = Some(f.rendered);
        Ok(())
    })
    .unwrap();
    out.expect("one frame")
}

#[test]
fn bands_approach_the_exact_vertex_path_as_they_multiply() {
    use crate::host::bands_study::{
        bands_error_px, bands_plan, colour_mad, exact_request, still_colour_mad,
    };
    use crate::model::rolling_shutter::Readout;
    let ctx = validated_context();
    let camera = small_barrel();
    let scene = crate::scene::builtin::grid(16);
    let frame = |p: &crate::plan::Plan| first_frame(ctx, p, &scene);
    let max = ctx.gpu().max_image_side();
    // What the warp's resampling leaves against the vertex path's raster, camera still.
    let floor = still_colour_mad(ctx, &camera, &scene).unwrap();
    // Rows, and columns read against the pan's sweep: band rects of either kind.
    for (readout, counts) in [
        (Readout::TopToBottom, &[1, 4, 16][..]),
        (Readout::RightToLeft, &[1, 16][..]),
    ] {
        let exact = crate::plan::Plan::from_request(&exact_request(&camera, readout), max);
        let exact = frame(&exact.unwrap());
        // One band is one render from the mid-frame pose: a global shutter's image. Above
        // the floor, the difference falls as the bands multiply.
        let excess: Vec<f64> = counts
            .iter()
            .map(|&k| {
                let p = bands_plan(ctx, &camera, readout, k).unwrap();
                colour_mad(&frame(&p), &exact).unwrap() - floor
            })
            .collect();
        assert!(
            excess.windows(2).all(|w| w[1] < 0.6 * w[0]),
            "{readout}: {excess:?} above {floor}"
        );
        let error: Vec<f64> = [4, 16]
            .iter()
            .map(|&k| bands_error_px(&camera, &scene, readout, k))
            .collect();
        assert!(error[1] < 0.3 * error[0], "{readout}: {error:?}");
    }
    assert_no_validation_messages(ctx);
}

/// The cube map's plan for `camera` through the bench's pan, read in `readout` order, in
/// `count` bands of lines (`count` 1: one set of faces from the mid-frame pose); `None`: the
/// camera still at the pan's first pose, the global shutter.
fn cube_bands_plan(
    camera: &crate::model::Camera,
    readout: crate::model::rolling_shutter::Readout,
    count: Option<u32>,
    max_image_side: u32,
) -> crate::plan::Plan {
    use crate::plan::{PathChoice, ReadoutSource, RenderRequest, Shutter};
    let (start, end) = crate::host::bands_study::pan();
    let mut request = RenderRequest::color(camera, PathChoice::cube(camera, 2.0));
    request.pose = start;
    request.previous_pose = start;
    let mut p = crate::plan::Plan::from_request(&request, max_image_side).unwrap();
    if count.is_some() {
        p.shutter = Shutter::Moving {
            readout,
            from: ReadoutSource::Request,
            frame: 0,
        };
        p.end_poses = vec![end];
        p.bands = count;
    }
    p
}

#[test]
fn cube_bands_approach_the_exact_vertex_path_as_they_multiply() {
    use crate::host::bands_study::{colour_mad, exact_request};
    use crate::model::rolling_shutter::Readout;
    let ctx = validated_context();
    // A lens both routes draw: the vertex path exactly per vertex, the cube map by its rays.
    let camera = small_barrel();
    let scene = crate::scene::builtin::grid(16);
    let frame = |p: &crate::plan::Plan| first_frame(ctx, p, &scene);
    let max = ctx.gpu().max_image_side();
    // What the cube map's resampling (faces, then the sphere warp) leaves against the vertex
    // path's raster, camera still at the pan's first pose.
    let floor = {
        let mut still = exact_request(&camera, Readout::TopToBottom);
        still.rolling_shutter = None;
        let vertex = frame(&crate::plan::Plan::from_request(&still, max).unwrap());
        let cube = frame(&cube_bands_plan(&camera, Readout::TopToBottom, None, max));
        colour_mad(&cube, &vertex).unwrap()
    };
    for (readout, counts) in [
        (Readout::TopToBottom, &[1, 4, 16][..]),
        (Readout::RightToLeft, &[1, 16][..]),
    ] {
        let exact = crate::plan::Plan::from_request(&exact_request(&camera, readout), max);
        let exact = frame(&exact.unwrap());
        // One band is one cube from the mid-frame pose: a global shutter's image. Above the
        // floor, the difference falls as the bands multiply.
        let excess: Vec<f64> = counts
            .iter()
            .map(|&k| {
                let p = cube_bands_plan(&camera, readout, Some(k), max);
                colour_mad(&frame(&p), &exact).unwrap() - floor
            })
            .collect();
        eprintln!("cube bands {readout} {counts:?}: {excess:?} above the floor {floor}");
        assert!(
            excess.windows(2).all(|w| w[1] < 0.6 * w[0]),
            "{readout}: {excess:?} above {floor}"
        );
        // The most bands: within a quarter of one band's excess, and a level of the floor.
        let (one, most) = (excess[0], excess[excess.len() - 1]);
        assert!(
            most < 0.25 * one && most < 1.0,
            "{readout}: {excess:?} above {floor}"
        );
    }
    assert_no_validation_messages(ctx);
}

/// The 200° fisheye in the room, lateral colour, turning about 1° during its second frame's
/// top-to-bottom readout, with `extra` tables.
fn banded_fisheye(extra: &str) -> SceneFile {
    scene_file(&format!(
        "[geometry]\nscene = \"room\"\n[optics]\ncamera = \"../cameras/fisheye_200.json\"\n\
         [sensor]\nrolling_shutter = \"top_to_bottom\"\n{BANDS_CHROMATIC}\
         [[poses]]\nrvec = [0.0, 0.0, 0.0]\ntvec = [0.0, 0.0, 0.0]\n\
         [[poses]]\nrvec = [0.0, -0.009, 0.0]\ntvec = [0.0, 0.0, 0.0]\n\
         end_rvec = [0.0, 0.009, 0.0]\nend_tvec = [0.0, 0.0, 0.0]\n{extra}"
    ))
}

#[test]
fn a_lens_no_pinhole_holds_takes_its_bands_through_the_cube_map() {
    let ctx = validated_context();
    let file = banded_fisheye(&budget(0.5));
    let scene = load_geometry(&file).unwrap();
    let mut p = plan(&file, &scene).unwrap();
    assert!(
        matches!(
            p.route,
            Route::Cube {
                chromatic: Some(_),
                ..
            }
        ),
        "{:?}",
        p.route
    );
    let k = p.bands.unwrap();
    let text = p.explain(None, &[]);
    assert!(
        text.contains("cube faces per band (6 pinhole renders each)")
            && text.contains(&format!("{k} bands leave"))
            && text.contains("the cube map's six faces are rendered once per band"),
        "{text}"
    );
    // Too tight a budget: refused, naming both keys.
    let tight = banded_fisheye(&budget(0.001));
    let e = plan(&tight, &scene).unwrap_err().to_string();
    assert!(
        e.contains("[sensor] rolling_shutter, [accuracy] max_error_px = 0.001")
            && e.contains("with 64 bands"),
        "{e}"
    );
    // Rendered small (lavapipe renders six faces per band): every pixel written once, by
    // its band's warp, the frame in bands unlike the still one.
    let camera = crate::model::Camera::fisheye(
        160,
        160,
        crate::model::Intrinsics {
            fx: 46.0,
            fy: 46.0,
            cx: 79.5,
            cy: 79.5,
        },
        crate::model::Fisheye::new([0.02, -0.004, 0.0005, 0.0], 0.0, Some(200.0)).unwrap(),
    )
    .unwrap();
    p.optics = crate::plan::Optics::Camera(camera);
    p.route = Route::Cube {
        side: 64,
        chromatic: Some([1.002, 1.0, 0.998]),
    };
    p.bands = Some(8);
    p.background = [0.0, 0.0, 0.0, 1.0];
    let mut out = Vec::new();
    let recorded = execute(ctx, &p, &scene, 0..2, &mut |f| {
        out.push(f.rendered.color.unwrap());
        Ok(())
    })
    .unwrap();
    assert!(recorded.has(PassKind::SphereWarp));
    for c in &out {
        let crate::imaging::Pixels::Rgba8(c) = &c.pixels else {
            panic!("8-bit colour expected");
        };
        assert!(c.iter().all(|p| p[3] == 255));
    }
    assert_ne!(out[0].pixels, out[1].pixels);
    assert_no_validation_messages(ctx);
}

#[test]
fn a_lens_request_renders_through_the_recorder_the_film_the_lens_pass_alone_renders() {
    // `vklens lens render` goes through the planner: its plan must record the image-based
    // model alone and give, pixel for pixel, what the pass renders when driven directly.
    use crate::lens::image_model::{channel_models, ModelOptions};
    use crate::pass::lens_render::{LensRenderOptions, LensRenderer};
    use crate::plan::{LensRequest, Plan};
    let ctx = validated_context();
    let scene = crate::scene::builtin::boxes();
    let prescription = crate::testing::shipped_lens("biconvex.50mm.dat");
    let (pixels, pitch_mm) = ((120, 80), 0.3);
    let (optics, pose) =
        crate::lens::frame_scene(&prescription, pixels, pitch_mm, None, None, None, &scene)
            .unwrap();
    let options = ModelOptions {
        samples: 4,
        ..ModelOptions::default()
    };
    let request = LensRequest {
        prescription,
        pixels,
        pitch_mm,
        f_number: None,
        options,
        chromatic: true,
        exr: true,
    };
    let p = Plan::from_lens_request(&request, &optics, pose).unwrap();
    assert!(matches!(
        p.route,
        Route::LensModel {
            samples: 4,
            chromatic: true,
            vignetting: true,
            ..
        }
    ));
    let mut film = None;
    let recorded = execute(ctx, &p, &scene, [0], &mut |f| {
        film = f.rendered.color;
        Ok(())
    })
    .unwrap();
    assert_eq!(recorded.pipelines.len(), 1);
    assert!(recorded.has(PassKind::LensModel));
    let film = film.expect("the plan's colour");
    let models = channel_models(&optics, &options, true).unwrap();
    let mut renderer = LensRenderer::new(ctx.gpu(), &models, LensRenderOptions::default()).unwrap();
    let mesh = crate::testing::upload_mesh(ctx, &scene.mesh, scene.texture.as_ref());
    let direct = renderer.render(ctx, &mesh, &pose).unwrap();
    let crate::imaging::Pixels::Rgba32F(planned) = &film.pixels else {
        panic!("an EXR request's film is float: {:?}", film.bit_depth);
    };
    assert_eq!(planned.len(), direct.pixels.len());
    assert!(direct.pixels.iter().any(|p| p[0] > 0.05), "a lit film");
    for (a, b) in planned.iter().zip(&direct.pixels) {
        assert_eq!(a[..3], b[..3]);
    }
    assert_no_validation_messages(ctx);
}

/// The k1 k2 grid of `distortion.toml` with `[render] path = path` and `extra` tables.
fn asked(path: &str, extra: &str) -> SceneFile {
    scene_file(&format!(
        "[geometry]\nscene = \"grid:8\"\n[optics]\ncamera = \"../cameras/barrel_k1k2.json\"\n\
         [accuracy]\nmax_error_px = 0.01\n[render]\npath = \"{path}\"\n{extra}"
    ))
}

#[test]
fn render_path_spells_the_paths_as_the_command_line_does_and_the_plan_takes_it() {
    use crate::plan::PathKind;
    for kind in PathKind::ALL {
        let file = asked(kind.name(), "");
        assert_eq!(file.path, Some(kind));
        let scene = load_geometry(&file).unwrap();
        let p = plan(&file, &scene).unwrap();
        let taken = match p.route {
            Route::Vertex { .. } => PathKind::Vertex,
            Route::Warp { .. } => PathKind::Warp,
            Route::Cube { .. } => PathKind::Cube,
            ref other => panic!("{kind}: {other:?}"),
        };
        assert_eq!(taken, kind);
        assert_eq!(p.path_asked, Some(kind));
        let text = p.explain(None, &[]);
        assert!(
            text.contains(&format!("path: {kind}, as [render] path asks")),
            "{text}"
        );
        // The reason names the request and what the others would have cost, not a
        // comparison the planner did not make.
        if kind != PathKind::Warp {
            assert!(text.contains("[render] path asks for it ("), "{text}");
        }
    }
    // Without the key, the planner's own choice and no path line.
    let own = SceneFile::load(&examples().join("distortion.toml")).unwrap();
    assert_eq!(own.path, None);
    let scene = load_geometry(&own).unwrap();
    let p = plan(&own, &scene).unwrap();
    assert!(!p.explain(None, &[]).contains("[render] path"));

    let e = error(
        "[geometry]\nscene = \"boxes\"\n[optics]\ncamera = \"c.json\"\n[render]\npath = \"fast\"\n",
    );
    assert!(
        e.contains("[render] path: expected one of vertex, warp, cube, found \"fast\""),
        "{e}"
    );
}

#[test]
fn render_path_refuses_what_the_path_cannot_deliver_naming_both_keys() {
    let scene_of = |f: &SceneFile| load_geometry(f).unwrap();
    let chromatic = asked("vertex", BANDS_CHROMATIC);
    let e = plan(&chromatic, &scene_of(&chromatic))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("[render] path = \"vertex\": [effects] chromatic_aberration needs the warp"),
        "{e}"
    );
    // IDs through the cube as asked (nearest); flow it cannot carry.
    let ids = asked("cube", "[outputs]\ncolor = true\nids = true\n");
    let p = plan(&ids, &scene_of(&ids)).unwrap();
    assert!(matches!(p.route, Route::Cube { .. }), "{:?}", p.route);
    let flow = asked("cube", "[outputs]\ncolor = true\nflow = true\n");
    let e = plan(&flow, &scene_of(&flow)).unwrap_err().to_string();
    assert!(
        e.contains("[render] path = \"cube\": a cube map carries no flow"),
        "{e}"
    );
    // IDs beside the warp's colour: Alg. 1 carries them, as the warp path does on the
    // command line.
    let warp_ids = asked("warp", "[outputs]\ncolor = true\nids = true\n");
    let p = plan(&warp_ids, &scene_of(&warp_ids)).unwrap();
    assert!(
        matches!(p.route, Route::WarpAndVertex { .. }),
        "{:?}",
        p.route
    );
}

#[test]
fn render_path_is_recorded_as_asked() {
    // The cube map on a lens a pinhole warp holds, where the planner takes Alg. 1 or the warp:
    // what is recorded is the cube's faces and the sphere warp, nothing of the others.
    let (p, recorded) = run(&asked("cube", ""));
    assert!(matches!(p.route, Route::Cube { .. }), "{:?}", p.route);
    assert!(recorded.has(PassKind::SphereWarp));
    assert!(!recorded.has(PassKind::Warp) && !recorded.has(PassKind::VertexRender));
}

#[test]
fn render_path_holds_for_a_camera_moving_during_its_readout() {
    // The warp asked for: the bands of lines draw the moving frame, and say they were asked.
    let file = banded_grid(&format!("{}[render]\npath = \"warp\"\n", budget(0.5)));
    let scene = load_geometry(&file).unwrap();
    let p = plan(&file, &scene).unwrap();
    assert!(matches!(p.route, Route::Warp { .. }), "{:?}", p.route);
    assert!(p.bands.is_some());
    assert!(
        p.explain(None, &[])
            .contains("[render] path asks for it (the exact vertex path"),
        "{}",
        p.explain(None, &[])
    );
    // The vertex path asked for: each vertex at its own line's pose.
    let file = banded_grid(&format!("{}[render]\npath = \"vertex\"\n", budget(0.5)));
    let p = plan(&file, &scene).unwrap();
    assert!(matches!(p.route, Route::Vertex { .. }), "{:?}", p.route);
    assert_eq!(p.bands, None);
}
