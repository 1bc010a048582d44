//! In-process lock step: the reference code runs from its shared library inside magdem, and a
//! `fix external pf/callback` hands magdem the positions every step; magdem returns the magnetic
//! forces (moments with the scene's mutual induction, dipole and gradient forces) from its own
//! core. LAMMPS sets the callback through its C API; LIGGGHTS through a small C++ shim (feature
//! `liggghts-shim`). Both libraries are loaded at run time, so magdem builds without them.

use super::deck::{self, FIX_ID};
use super::{dump, Engine, ReferenceError, ReferenceRun};
use crate::core::simulation::ForceField;
use crate::core::state::{State, Vec3};
use crate::io::trajectory::Cost;
use crate::scene::Scene;
use libloading::Library;
use std::ffi::{c_char, c_int, c_void, CString};
use std::path::Path;
use std::sync::Mutex;

/// `void (*)(void *data, bigint step, int nlocal, tagint *ids, double **x, double **f)` with
/// bigint = int64 and tagint = int, as both Debian builds use (LAMMPS_SMALLBIG).
type Callback = extern "C" fn(*mut c_void, i64, c_int, *mut c_int, *mut *mut f64, *mut *mut f64);

/// One instance at a time: the libraries keep global (MPI) state.
static INSTANCE: Mutex<()> = Mutex::new(());

fn library_name(engine: Engine) -> &'static str {
    engine.dialect().library()
}

/// Whether the in-process route can run for `engine` here (loads the library once).
pub fn available(engine: Engine) -> Result<(), String> {
    load(engine).map(|_| ())
}

/// Magdem's side of the lock step: the magnetic force field and a state to evaluate it on.
struct Coupler {
    field: ForceField,
    state: State,
    steps_per_frame: i64,
    /// Moments at each output frame, to store in the trajectory.
    frame_moments: Vec<Vec<Vec3>>,
    error: Option<String>,
}

extern "C" fn magnetic_forces(
    data: *mut c_void,
    step: i64,
    nlocal: c_int,
    ids: *mut c_int,
    x: *mut *mut f64,
    f: *mut *mut f64,
) {
    // SAFETY: `data` is the Coupler registered with the callback and outlives the run; the
    // engine passes `nlocal` rows of ids, positions and forces.
    let coupler = unsafe { &mut *(data as *mut Coupler) };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let n = coupler.state.particles.len();
        if nlocal as usize != n {
            return Err(format!("the engine passed {nlocal} atoms, the scene has {n} (MPI runs need the files route)"));
        }
        let positions = coupler.state.particles.position.write();
        for k in 0..n {
            let (id, row) = unsafe { (*ids.add(k) as usize, std::slice::from_raw_parts(*x.add(k), 3)) };
            if id == 0 || id > n {
                return Err(format!("atom id {id} outside 1..={n}"));
            }
            positions[id - 1] = Vec3::new(row[0], row[1], row[2]);
        }
        coupler.field.evaluate(&mut coupler.state, 0.0);
        for k in 0..n {
            let id = unsafe { *ids.add(k) } as usize;
            let force = coupler.state.fields.force[id - 1];
            let out = unsafe { std::slice::from_raw_parts_mut(*f.add(k), 3) };
            out.copy_from_slice(force.as_slice());
        }
        if step % coupler.steps_per_frame == 0 {
            coupler.frame_moments.push(coupler.state.fields.moment.clone());
        }
        Ok(())
    }));
    let failure = match result {
        Ok(Ok(())) => return,
        Ok(Err(message)) => message,
        Err(_) => "panic in magdem's force callback".to_string(),
    };
    coupler.error.get_or_insert(failure);
    for k in 0..nlocal as usize {
        unsafe { std::slice::from_raw_parts_mut(*f.add(k), 3) }.fill(0.0);
    }
}

/// The engine's library (and its callback shim), loaded once per process and kept: unloading and
/// reloading LIGGGHTS runs its static style registration again, which it reports as collisions.
fn load(engine: Engine) -> Result<&'static (Library, Option<Library>), String> {
    type Loaded = Result<&'static (Library, Option<Library>), String>;
    static LOADED: std::sync::Mutex<Vec<(&'static str, Loaded)>> = std::sync::Mutex::new(Vec::new());
    let mut loaded = LOADED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some((_, result)) = loaded.iter().find(|(name, _)| *name == engine.name()) {
        return result.clone();
    }
    let open = || -> Result<(Library, Option<Library>), String> {
        let shim = engine.dialect().callback_shim().map_err(String::from)?;
        // SAFETY: loading a system library runs its initialisers, which touch nothing of ours; the
        // symbols are used with their C signatures from library.h.
        let name = library_name(engine);
        let library = unsafe { Library::new(name) }.map_err(|e| format!("cannot load {name}: {e}"))?;
        let shim = shim.map(|path| unsafe { Library::new(path) }.map_err(|e| e.to_string())).transpose()?;
        Ok((library, shim))
    };
    let result: Loaded = open().map(|pair| &*Box::leak(Box::new(pair)));
    loaded.push((engine.name(), result.clone()));
    result
}

/// A loaded engine instance.
struct Instance {
    engine: Engine,
    library: &'static Library,
    shim: Option<&'static Library>,
    handle: *mut c_void,
}

impl Instance {
    fn open(engine: Engine, log: &Path) -> Result<Self, ReferenceError> {
        let fail = |why: String| ReferenceError::Unsupported {
            engine: engine.name(),
            term: "the in-process lock step".into(),
            why,
        };
        let (library, shim) = load(engine).map_err(fail)?;
        let shim = shim.as_ref();
        let args: Vec<CString> = ["magdem", "-screen", "none", "-log", log.to_str().unwrap_or("log.engine")]
            .iter()
            .map(|a| CString::new(*a).expect("no NUL"))
            .collect();
        let mut argv: Vec<*mut c_char> = args.iter().map(|a| a.as_ptr() as *mut c_char).collect();
        let mut handle: *mut c_void = std::ptr::null_mut();
        unsafe {
            if !engine.dialect().open_returns_instance() {
                // LIGGGHTS 3.8: void lammps_open_no_mpi(int, char **, void **)
                let open: libloading::Symbol<unsafe extern "C" fn(c_int, *mut *mut c_char, *mut *mut c_void)> =
                    library.get(b"lammps_open_no_mpi").map_err(|e| fail(e.to_string()))?;
                open(argv.len() as c_int, argv.as_mut_ptr(), &mut handle);
            } else {
                // LAMMPS 2021: void *lammps_open_no_mpi(int, char **, void **), handle returned
                let open: libloading::Symbol<
                    unsafe extern "C" fn(c_int, *mut *mut c_char, *mut *mut c_void) -> *mut c_void,
                > = library.get(b"lammps_open_no_mpi").map_err(|e| fail(e.to_string()))?;
                handle = open(argv.len() as c_int, argv.as_mut_ptr(), std::ptr::null_mut());
            }
        }
        if handle.is_null() {
            return Err(fail("lammps_open_no_mpi returned no instance".into()));
        }
        Ok(Self { engine, library, shim, handle })
    }

    fn command(&self, line: &str) -> Result<(), ReferenceError> {
        let c = CString::new(line).map_err(|e| ReferenceError::Io(std::io::Error::other(e)))?;
        unsafe {
            let command: libloading::Symbol<unsafe extern "C" fn(*mut c_void, *const c_char) -> *mut c_char> =
                self.library.get(b"lammps_command").map_err(|e| ReferenceError::Io(std::io::Error::other(e)))?;
            command(self.handle, c.as_ptr());
        }
        Ok(())
    }

    fn set_callback(&self, callback: Callback, data: *mut c_void) -> Result<(), ReferenceError> {
        let id = CString::new(FIX_ID).expect("no NUL");
        let fail =
            |why: String| ReferenceError::Unsupported { engine: self.engine.name(), term: "fix external".into(), why };
        unsafe {
            match self.shim {
                Some(shim) => {
                    let set: libloading::Symbol<
                        unsafe extern "C" fn(*mut c_void, *const c_char, Callback, *mut c_void) -> c_int,
                    > = shim.get(b"magdem_liggghts_set_callback").map_err(|e| fail(e.to_string()))?;
                    match set(self.handle, id.as_ptr(), callback, data) {
                        0 => Ok(()),
                        code => Err(fail(format!("the shim could not find fix external '{FIX_ID}' (code {code})"))),
                    }
                }
                None => {
                    let set: libloading::Symbol<
                        unsafe extern "C" fn(*mut c_void, *const c_char, Callback, *mut c_void),
                    > = self.library.get(b"lammps_set_fix_external_callback").map_err(|e| fail(e.to_string()))?;
                    set(self.handle, id.as_ptr(), callback, data);
                    Ok(())
                }
            }
        }
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        unsafe {
            if let Ok(close) = self.library.get::<unsafe extern "C" fn(*mut c_void)>(b"lammps_close") {
                close(self.handle);
            }
        }
    }
}

/// Runs a magnetic scene in `engine` with magdem's magnetic forces in lock step (every step).
pub fn run_coupled(engine: Engine, scene: &Scene, dir: &Path, output: &Path) -> Result<ReferenceRun, ReferenceError> {
    let start = std::time::Instant::now();
    let field = scene.magnetic_force_field().ok_or_else(|| ReferenceError::Unsupported {
        engine: engine.name(),
        term: "the in-process lock step".into(),
        why: "the scene has no magnetic term to couple".into(),
    })?;
    std::fs::create_dir_all(dir)?;
    let dir = dir.canonicalize()?;
    let written = deck::write(engine, scene, &dir)?;
    let text = std::fs::read_to_string(dir.join(&written.input))?;
    let log = output.with_extension(format!("{}.log", engine.name()));
    let log = std::env::current_dir()?.join(log);

    let _guard = INSTANCE.lock().unwrap_or_else(|e| e.into_inner());
    let instance = Instance::open(engine, &log)?;
    let absolute = |name: &Path| dir.join(name).display().to_string();
    // Included fix files are read here (the engine would resolve them against magdem's cwd).
    let mut lines = vec![];
    for line in text.lines() {
        match line.trim().strip_prefix("include ") {
            Some(name) => lines.extend(std::fs::read_to_string(dir.join(name.trim()))?.lines().map(str::to_string)),
            None => lines.push(line.to_string()),
        }
    }
    let mut run_line = None;
    for line in &lines {
        let line = line.trim();
        if line.starts_with("run ") {
            run_line = Some(line.to_string());
            continue;
        }
        let line = line
            .replace(&format!(" {}", written.data.display()), &format!(" {}", absolute(&written.data)))
            .replace(&format!(" {}", written.dump), &format!(" {}", absolute(Path::new(&written.dump))));
        instance.command(&line)?;
    }
    let mut coupler = Box::new(Coupler {
        field,
        state: scene.initial_state(),
        steps_per_frame: scene.steps_per_frame() as i64,
        frame_moments: vec![],
        error: None,
    });
    instance.set_callback(magnetic_forces, &mut *coupler as *mut Coupler as *mut c_void)?;
    instance.command(run_line.as_deref().unwrap_or("run 0"))?;
    drop(instance);
    if let Some(message) = coupler.error.take() {
        return Err(ReferenceError::Failed {
            engine: engine.name(),
            code: None,
            log: log.display().to_string(),
            tail: message,
        });
    }
    let mut frames = dump::read(engine, &dir.join(&written.dump), scene)?;
    for (state, moments) in frames.iter_mut().zip(&coupler.frame_moments) {
        state.fields.moment.clone_from(moments);
    }
    super::store(
        engine,
        "velocity-verlet (nve/sphere), magnetic forces from magdem every step",
        scene,
        output,
        &frames,
        Cost { wall_time: start.elapsed(), threads: 1 },
    )?;
    Ok(ReferenceRun { frames: frames.len(), log, wall_time: start.elapsed() })
}
