//! `plie._plie`: the Python bindings of plie (pyo3), wrapped by the `plie` Python package
//! (`python/plie/`). Scenes, cameras and camera paths, environments (octree + P-LIE, SPEC §4) built,
//! saved and loaded, rendering to numpy arrays of linear radiance (SPEC §2) with the GIL released,
//! and shadow queries (SPEC §5). The library calls go through [`engine`]; this file only converts
//! between Python and Rust.

mod engine;

use std::path::PathBuf;
use std::sync::Arc;

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray1, PyReadonlyArray2, PyReadonlyArray3};
use pyo3::create_exception;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use engine::{BuildOptions, Env, LoadedScene, RenderOptions, Segment};

create_exception!(_plie, PlieError, PyValueError, "An error of the plie library (bad input, parameters, files).");

/// The library's error as a Python exception with its message: `FileNotFoundError` / `OSError` for
/// files that cannot be read or written, `PlieError` (a `ValueError`) for everything else.
fn py_err(e: engine::Error) -> PyErr {
    let msg = e.to_string();
    match &e {
        engine::Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(msg)
        }
        engine::Error::Io { .. } => PyOSError::new_err(msg),
        _ => PlieError::new_err(msg),
    }
}

/// A scene: a built-in one or a loaded file.
#[pyclass(module = "plie", frozen)]
struct Scene {
    inner: Arc<LoadedScene>,
}

#[pymethods]
impl Scene {
    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.scene.name.clone()
    }

    /// Number of triangles (lights' included).
    #[getter]
    fn triangle_count(&self) -> usize {
        self.inner.scene.triangles.len()
    }

    /// Number of lights.
    #[getter]
    fn light_count(&self) -> usize {
        self.inner.scene.lights.len()
    }

    /// The scene's camera, or one framing the scene (what `plie render` uses without `--eye`).
    #[getter]
    fn camera(&self) -> Camera {
        Camera { inner: self.inner.scene.camera_or_default() }
    }

    /// The triangles' vertices, shape (T, 3, 3), float32.
    fn vertices<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v: Vec<f32> =
            self.inner.scene.triangles.iter().flat_map(|t| t.v.iter().flat_map(|p| p.to_array())).collect();
        let n = self.inner.scene.triangles.len();
        Ok(PyArray1::from_vec(py, v).reshape([n, 3, 3])?.into_any())
    }

    /// Per triangle, the light it belongs to, or -1; shape (T,), int64.
    fn triangle_lights<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        let v: Vec<i64> = self.inner.scene.tri_light.iter().map(|l| l.map_or(-1, |l| l.0 as i64)).collect();
        PyArray1::from_vec(py, v)
    }

    fn __repr__(&self) -> String {
        let s = &self.inner.scene;
        format!("<plie.Scene '{}': {} triangles, {} lights>", s.name, s.triangles.len(), s.lights.len())
    }
}

/// A pinhole camera: eye, target looked at, up direction, vertical field of view in degrees.
#[pyclass(module = "plie", frozen)]
#[derive(Clone)]
struct Camera {
    inner: engine::Camera,
}

type V3 = (f32, f32, f32);

fn v3(v: V3) -> glam::Vec3 {
    glam::Vec3::new(v.0, v.1, v.2)
}

fn t3(v: glam::Vec3) -> V3 {
    (v.x, v.y, v.z)
}

#[pymethods]
impl Camera {
    #[new]
    #[pyo3(signature = (eye, target, up=(0.0, 1.0, 0.0), fov=60.0))]
    fn new(eye: V3, target: V3, up: V3, fov: f32) -> PyResult<Camera> {
        let inner = engine::Camera::new(v3(eye), v3(target), v3(up), fov).map_err(py_err)?;
        Ok(Camera { inner })
    }

    #[getter]
    fn eye(&self) -> V3 {
        t3(self.inner.eye)
    }

    #[getter]
    fn target(&self) -> V3 {
        t3(self.inner.target)
    }

    #[getter]
    fn up(&self) -> V3 {
        t3(self.inner.up)
    }

    #[getter]
    fn fov(&self) -> f32 {
        self.inner.fov_deg
    }

    fn __eq__(&self, other: &Camera) -> bool {
        self.inner == other.inner
    }

    fn __repr__(&self) -> String {
        let c = &self.inner;
        format!("plie.Camera(eye={:?}, target={:?}, up={:?}, fov={})", t3(c.eye), t3(c.target), t3(c.up), c.fov_deg)
    }
}

/// Keyframed cameras of a walkthrough (the JSON of `plie render --camera-path`).
#[pyclass(module = "plie", frozen)]
struct CameraPath {
    inner: engine::CameraPath,
}

#[pymethods]
impl CameraPath {
    /// Reads a camera path file.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<CameraPath> {
        Ok(CameraPath { inner: engine::camera_path(None, Some(&path)).map_err(py_err)? })
    }

    /// Parses a camera path from JSON text.
    #[staticmethod]
    fn from_json(text: &str) -> PyResult<CameraPath> {
        Ok(CameraPath { inner: engine::camera_path(Some(text), None).map_err(py_err)? })
    }

    /// First and last frame, both included.
    #[getter]
    fn frames(&self) -> (u32, u32) {
        self.inner.frames()
    }

    /// The camera at `frame`.
    fn camera(&self, frame: u32) -> PyResult<Camera> {
        Ok(Camera { inner: self.inner.camera(frame).map_err(py_err)? })
    }

    fn __repr__(&self) -> String {
        let (a, b) = self.inner.frames();
        format!("<plie.CameraPath: frames {a}..{b}, {} keyframes>", self.inner.keyframes.len())
    }
}

/// An octree and its P-LIE for one scene: built once, saved, loaded, and used by any number of
/// renders and shadow queries.
#[pyclass(module = "plie", frozen)]
struct Environment {
    inner: Arc<Env>,
    scene: Arc<LoadedScene>,
}

fn json_to_py<'py>(py: Python<'py>, s: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (s,))
}

#[pymethods]
impl Environment {
    /// Builds the octree and the P-LIE for `scene`; the keywords are `plie build`'s options and
    /// defaults.
    #[staticmethod]
    #[pyo3(signature = (scene, *, max_triangles=200, max_depth=None, no_grids=false, no_regions=false,
        no_propagation=false, refine=None, max_split_depth=2, max_blockers=None, blocker_cap=Some(64),
        lift_clips=Some(plie::DEFAULT_LIFT_CLIPS), cell_clips=Some(plie::DEFAULT_CELL_CLIPS)))]
    #[allow(clippy::too_many_arguments)]
    fn build(
        py: Python<'_>,
        scene: &Scene,
        max_triangles: usize,
        max_depth: Option<u32>,
        no_grids: bool,
        no_regions: bool,
        no_propagation: bool,
        refine: Option<Vec<String>>,
        max_split_depth: u32,
        max_blockers: Option<Bound<'_, PyAny>>,
        blocker_cap: Option<u32>,
        lift_clips: Option<usize>,
        cell_clips: Option<usize>,
    ) -> PyResult<Environment> {
        let defaults = BuildOptions::default();
        let max_blockers = max_blockers.map(|b| b.str().map(|s| s.to_string())).transpose()?;
        let o = BuildOptions {
            max_triangles,
            max_depth: max_depth.unwrap_or(defaults.max_depth),
            no_grids,
            no_regions,
            no_propagation,
            refine: refine.unwrap_or_default(),
            max_split_depth,
            max_blockers,
            blocker_cap,
        };
        let params = o.params(true).map_err(py_err)?;
        let s = scene.inner.clone();
        let env = py.detach(|| Env::build(&s, params, lift_clips, cell_clips)).map_err(py_err)?;
        Ok(Environment { inner: Arc::new(env), scene: s })
    }

    /// Saves it as a `.plie` file (atomically, like `plie build`); returns the bytes written.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<u64> {
        py.detach(|| self.inner.save(&self.scene, &path)).map_err(py_err)
    }

    /// Loads a `.plie` file built for `scene` (checked: format, integrity, scene, octree).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf, scene: &Scene) -> PyResult<Environment> {
        let s = scene.inner.clone();
        let env = py.detach(|| Env::load(&s, &path)).map_err(py_err)?;
        Ok(Environment { inner: Arc::new(env), scene: s })
    }

    /// Loads the bytes of a `.plie` file (e.g. from Ray's object store) built for `scene`, with the
    /// same checks as `load`.
    #[staticmethod]
    fn from_bytes(py: Python<'_>, data: &Bound<'_, PyBytes>, scene: &Scene) -> PyResult<Environment> {
        let s = scene.inner.clone();
        let bytes = data.as_bytes();
        let env = py.detach(|| Env::from_bytes(&s, bytes)).map_err(py_err)?;
        Ok(Environment { inner: Arc::new(env), scene: s })
    }

    /// The scene it was built for.
    #[getter]
    fn scene(&self) -> Scene {
        Scene { inner: self.scene.clone() }
    }

    /// Construction figures (a dict, as `plie build --json`'s), or None when loaded.
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        self.inner.stats_json.as_deref().map(|s| json_to_py(py, s)).transpose()
    }

    /// Seconds the build or the load took.
    #[getter]
    fn seconds(&self) -> f64 {
        self.inner.seconds
    }

    /// The fastest visibility mode it supports (`render`'s default with it).
    #[getter]
    fn visibility(&self) -> &'static str {
        self.inner.best_mode().name()
    }

    /// Octree leaves.
    #[getter]
    fn leaves(&self) -> usize {
        self.inner.leaves()
    }

    fn __repr__(&self) -> String {
        format!("<plie.Environment of '{}': {} leaves>", self.scene.scene.name, self.inner.leaves())
    }
}

/// Loads a built-in scene by name or a scene file (.obj with its .mtl, .gltf, .glb).
#[pyfunction]
#[pyo3(signature = (path_or_builtin, *, allow_outside_paths=false))]
fn load_scene(py: Python<'_>, path_or_builtin: PathBuf, allow_outside_paths: bool) -> PyResult<Scene> {
    let name = path_or_builtin.to_string_lossy().into_owned();
    let s = py.detach(|| LoadedScene::load(&name, allow_outside_paths)).map_err(py_err)?;
    Ok(Scene { inner: Arc::new(s) })
}

/// The names of the built-in scenes.
#[pyfunction]
fn builtin_scenes() -> Vec<&'static str> {
    plie::scene::builtin::NAMES.to_vec()
}

/// Renders `scene` as `plie render` does with the same options (the same pixels, bit for bit):
/// returns linear radiance, shape (height, width, 3), float32; with `return_stats`, also a dict of
/// figures. The GIL is released while rendering.
#[pyfunction]
#[pyo3(signature = (scene, *, camera=None, visibility=None, env=None, width=398, height=398, eye_rays=2,
    shadow_rays=25, seed=0, spp=None, integrator="direct", max_path_depth=5, rr_depth=None, nee="power",
    threads=None, return_stats=false))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Scene,
    camera: Option<&Camera>,
    visibility: Option<&str>,
    env: Option<&Environment>,
    width: u32,
    height: u32,
    eye_rays: u32,
    shadow_rays: u32,
    seed: u64,
    spp: Option<u32>,
    integrator: &str,
    max_path_depth: i32,
    rr_depth: Option<u32>,
    nee: &str,
    threads: Option<usize>,
    return_stats: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let o = RenderOptions {
        width,
        height,
        eye_rays,
        shadow_rays,
        seed,
        spp,
        integrator: integrator.into(),
        max_path_depth,
        rr_depth,
        nee: nee.into(),
        threads,
    };
    let s = scene.inner.clone();
    let cam = camera.map(|c| c.inner);
    let e = env.map(|e| e.inner.clone());
    let vis = visibility.map(str::to_string);
    let img = py.detach(|| engine::render(&s, cam, vis.as_deref(), e.as_deref(), &o)).map_err(py_err)?;
    let flat: Vec<f32> = img.pixels.iter().flat_map(|p| p.to_array()).collect();
    let array = PyArray1::from_vec(py, flat).reshape([img.height as usize, img.width as usize, 3])?.into_any();
    if !return_stats {
        return Ok(array);
    }
    let stats = json_to_py(py, &serde_json::to_string(&img.stats).map_err(|e| PlieError::new_err(e.to_string()))?)?;
    let d = stats.cast_into::<PyDict>()?;
    d.set_item("visibility", img.mode.name())?;
    d.set_item("seconds", img.seconds)?;
    Ok((array, d).into_pyobject(py)?.into_any())
}

/// Shadow queries: segment i runs from `x[i]` (on triangle `origin_triangle[i]`, or -1 for none) to
/// `y[i]` on light `light[i]`; true where another triangle blocks the open segment.
#[pyfunction]
#[pyo3(signature = (scene, x, y, light, origin_triangle, visibility=None, env=None))]
#[allow(clippy::too_many_arguments)]
fn _occluded<'py>(
    py: Python<'py>,
    scene: &Scene,
    x: PyReadonlyArray2<'py, f64>,
    y: PyReadonlyArray2<'py, f64>,
    light: PyReadonlyArray1<'py, i64>,
    origin_triangle: PyReadonlyArray1<'py, i64>,
    visibility: Option<&str>,
    env: Option<&Environment>,
) -> PyResult<Bound<'py, PyArray1<bool>>> {
    let (x, y, light, tri) = (x.as_array(), y.as_array(), light.as_array(), origin_triangle.as_array());
    let n = x.nrows();
    if x.ncols() != 3 || y.shape() != [n, 3] || light.len() != n || tri.len() != n {
        return Err(PyValueError::new_err(format!(
            "shadow segments: x and y must have shape (N, 3) and light, origin_triangle (N,); got x {:?}, y {:?}, light {:?}, origin_triangle {:?}",
            x.shape(),
            y.shape(),
            light.shape(),
            tri.shape()
        )));
    }
    let segments: Vec<Segment> = (0..n)
        .map(|i| Segment {
            x: [x[[i, 0]], x[[i, 1]], x[[i, 2]]],
            y: [y[[i, 0]], y[[i, 1]], y[[i, 2]]],
            light: light[i],
            origin_tri: (tri[i] != -1).then_some(tri[i]),
        })
        .collect();
    let s = scene.inner.clone();
    let e = env.map(|e| e.inner.clone());
    let vis = visibility.map(str::to_string);
    let out = py.detach(|| engine::occluded(&s, &segments, vis.as_deref(), e.as_deref())).map_err(py_err)?;
    Ok(PyArray1::from_vec(py, out))
}

/// Writes `image` (shape (H, W, 3), linear radiance) as `plie render -o` does: PNG (tone-mapped sRGB,
/// radiance scaled by 2^`exposure` first), EXR or PFM (linear) by the extension, atomically.
#[pyfunction]
#[pyo3(signature = (path, image, *, exposure=0.0))]
fn save_image(py: Python<'_>, path: PathBuf, image: PyReadonlyArray3<'_, f32>, exposure: f32) -> PyResult<()> {
    let a = image.as_array();
    let shape = a.shape().to_vec();
    if shape.len() != 3 || shape[2] != 3 {
        return Err(PyValueError::new_err(format!("save_image: image must have shape (H, W, 3), not {shape:?}")));
    }
    let rgb: Vec<f32> = a.iter().copied().collect();
    let (h, w) = (u32::try_from(shape[0]).unwrap_or(u32::MAX), u32::try_from(shape[1]).unwrap_or(u32::MAX));
    py.detach(|| engine::save_image(&path, w, h, &rgb, exposure)).map_err(py_err)
}

/// The native module.
#[pymodule]
fn _plie(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("PlieError", m.py().get_type::<PlieError>())?;
    m.add_class::<Scene>()?;
    m.add_class::<Camera>()?;
    m.add_class::<CameraPath>()?;
    m.add_class::<Environment>()?;
    m.add_function(wrap_pyfunction!(load_scene, m)?)?;
    m.add_function(wrap_pyfunction!(builtin_scenes, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(_occluded, m)?)?;
    m.add_function(wrap_pyfunction!(save_image, m)?)?;
    Ok(())
}
