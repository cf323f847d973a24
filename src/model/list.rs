// The one list of camera models (after COLMAP's `CAMERA_MODEL_CASES` in `sensor/models.h`):
// every table, enum and switch over the models is generated from these rows.
//
// This file is included twice: by `src/model/lens.rs`, whose `camera_models!` builds
// `ModelKind`, `Lens` and their dispatch, the names and the planner's costs; and by `build.rs`,
// whose `camera_models!` writes the shaders' model ids, includes and dispatch. So it holds this
// one invocation and nothing else. `docs/how-it-works.md#adding-a-camera-model` says how to add a row.
//
// Per row:
//   Variant = id        ModelKind::Variant, Lens::Variant; the shaders' VKL_MODEL (stable:
//                       append, never renumber)
//   rust                the model's type, in `src/model/<module>.rs`, implementing RayModel
//   name                `"model"` in vklens camera files, and the C API's `vkl_camera_model`
//   params              named[...]: the parameters a vklens JSON file gives as named numbers, in
//                       the order `RayModel::from_params` takes them; custom("keys"): lists or
//                       flags, read by `io::models`, and the keys as `vklens --help` names them
//   glsl                (VKL_MODEL_<DEFINE>, vkl_<prefix>_project / vkl_<prefix>_unproject,
//                       the include under glsl/include/ holding them, "" for none)
//   inverse_cost        the GPU inverse's cost per pixel relative to the fisheye's 70 ns (f32,
//                       lavapipe): each model's 1080p inverse time over the fisheye's in two
//                       `vklens bench models` runs (docs/benchmarks.md)
//   focal_length        whether fx fy are a focal length a pinhole image can share (not where
//                       the model's polynomials carry the scale, nor for a panorama's pixels
//                       per radian)
camera_models! {
    standard: {
        /// OpenCV's standard model (k1..k6, p1 p2, s1..s4, τx τy), and Brown's radial model.
        Standard = 0, name: "opencv", params: custom("dist_coeffs: 4, 5, 8, 12 or 14 of OpenCV's"),
            glsl: (OPENCV), inverse_cost: 1.0, focal_length: true;
    }
    rays: {
        /// OpenCV's fisheye model (Kannala–Brandt k1..k4).
        Fisheye = 1, rust: fisheye::Fisheye, name: "opencv_fisheye",
            params: custom("dist_coeffs k1..k4, optional alpha skew and max_fov_deg"),
            glsl: (FISHEYE, fisheye, ""), inverse_cost: 1.0, focal_length: true;
        /// Mei's unified model with radial-tangential distortion.
        Omni = 2, rust: omni::Omni, name: "omni", params: custom("xi, dist_coeffs k1 k2 p1 p2"),
            glsl: (OMNI, omni, "models/omni.glsl"), inverse_cost: 2.6, focal_length: true;
        /// Basalt's unified camera model.
        Ucm = 3, rust: ucm::Ucm, name: "ucm", params: named["alpha"],
            glsl: (UCM, ucm, "models/ucm.glsl"), inverse_cost: 0.65, focal_length: true;
        /// The enhanced unified camera model.
        Eucm = 4, rust: eucm::Eucm, name: "eucm", params: named["alpha", "beta"],
            glsl: (EUCM, eucm, "models/eucm.glsl"), inverse_cost: 0.65, focal_length: true;
        /// The double sphere model.
        DoubleSphere = 5, rust: double_sphere::DoubleSphere, name: "double_sphere",
            params: named["xi", "alpha"],
            glsl: (DOUBLE_SPHERE, ds, "models/double_sphere.glsl"), inverse_cost: 0.65,
            focal_length: true;
        /// Devernay and Faugeras' field-of-view model.
        Fov = 6, rust: fov::Fov, name: "fov", params: named["omega"],
            glsl: (FOV, fov, "models/fov.glsl"), inverse_cost: 0.8, focal_length: true;
        /// The equirectangular panorama.
        Equirectangular = 7, rust: equirect::Equirectangular, name: "equirectangular",
            params: custom("none; default fx..cy: the whole sphere"),
            glsl: (EQUIRECTANGULAR, equirect, "models/equirectangular.glsl"), inverse_cost: 0.6,
            focal_length: false;
        /// NVIDIA's f-theta model.
        FTheta = 8, rust: ftheta::FTheta, name: "ftheta", params: custom("NCore's keys"),
            glsl: (FTHETA, ftheta, "models/ftheta.glsl"), inverse_cost: 1.6, focal_length: false;
        /// Scaramuzza's OCamCalib model.
        Ocam = 9, rust: ocam::Ocam, name: "ocam", params: custom("poly, inverse_poly, c, d, e"),
            glsl: (OCAM, ocam, "models/ocam.glsl"), inverse_cost: 0.75, focal_length: false;
        /// Fitzgibbon's division model (COLMAP's).
        Division = 10, rust: division::Division, name: "division", params: named["k"],
            glsl: (DIVISION, division, "models/division.glsl"), inverse_cost: 0.8,
            focal_length: true;
        /// COLMAP's thin-prism fisheyes (THIN_PRISM_FISHEYE, RAD_TAN_THIN_PRISM_FISHEYE).
        ThinPrismFisheye = 11, rust: thin_prism::ThinPrismFisheye, name: "thin_prism_fisheye",
            params: custom("radial, p, s, radial_first"),
            glsl: (THIN_PRISM_FISHEYE, tp, "models/thin_prism_fisheye.glsl"), inverse_cost: 3.0,
            focal_length: true;
    }
}
