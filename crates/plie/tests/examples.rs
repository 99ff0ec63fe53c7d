//! Runs the programs of `examples/` (one per way a user comes in, issue 14), so they stay working:
//! each asserts what it shows (exact modes agree, a file loads back, a bad one is refused).

#[allow(dead_code)] // `main`: the tests call `run`
#[path = "../examples/render_scene.rs"]
mod render_scene;

#[allow(dead_code)] // `main`: the tests call `run`
#[path = "../examples/build_save_load.rs"]
mod build_save_load;

#[allow(dead_code)] // `main`: the tests call `run`
#[path = "../examples/shadow_queries.rs"]
mod shadow_queries;

#[test]
fn render_scene_runs() {
    render_scene::run("cornell-cube-2").unwrap();
}

#[test]
fn build_save_load_runs() {
    build_save_load::run("cornell-cube-4").unwrap();
}

#[test]
fn shadow_queries_runs() {
    shadow_queries::run("dragon").unwrap();
}
