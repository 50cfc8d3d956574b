// The page: starts the engine (sylva_web.wasm, built by `./run web`) on the canvas, runs it
// each animation frame, and passes the panel's choices, the pointer, the keys and dropped
// files to it. `window.sylva` holds the figures the page shows, for scripts and tests.

import init, { App, presets } from './sylva_web.js';

const $ = (id) => document.getElementById(id);
const canvas = $('forest');

// What scripts (and the browser test) read: the app, frames drawn, the time from navigation
// to the first frame (ms) and how long of it the engine took to start (ms: module, forest,
// renderer), the latest figures.
const sylva = { app: null, frames: 0, firstFrameMs: null, startMs: null, fps: 0, busy: false, figures: {} };
window.sylva = sylva;

function showError(e) {
    const message = e && e.message ? e.message : String(e);
    $('error').textContent = message;
    $('error').hidden = false;
}

function clearError() {
    $('error').hidden = true;
    $('error').textContent = '';
}

// Long work (growing a scene, synthesising a wind) runs on the page's thread: say what is
// being done and let the page paint before starting it. No frame is drawn meanwhile.
async function busy(what, work) {
    sylva.busy = true;
    $('status').textContent = `${what}…`;
    await new Promise((resolve) => setTimeout(resolve, 30));
    try {
        const done = await work();
        clearError();
        $('status').textContent = typeof done === 'string' ? done : '';
    } catch (e) {
        showError(e);
        $('status').textContent = '';
    } finally {
        sylva.busy = false;
    }
}

function sizeCanvas() {
    const dpr = Math.min(window.devicePixelRatio || 1, 2);
    const w = Math.max(1, Math.round(canvas.clientWidth * dpr));
    const h = Math.max(1, Math.round(canvas.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) {
        canvas.width = w;
        canvas.height = h;
        if (sylva.app) sylva.app.resize(w, h);
    }
}

// Pointer: one finger or the mouse orbits, two fingers pinch to zoom.
const pointers = new Map();
let pinch = null;
canvas.addEventListener('pointerdown', (e) => {
    canvas.setPointerCapture(e.pointerId);
    pointers.set(e.pointerId, [e.clientX, e.clientY]);
    canvas.focus();
});
canvas.addEventListener('pointermove', (e) => {
    const was = pointers.get(e.pointerId);
    if (!was || !sylva.app) return;
    pointers.set(e.pointerId, [e.clientX, e.clientY]);
    if (pointers.size === 1) {
        sylva.app.drag(e.clientX - was[0], e.clientY - was[1]);
    } else if (pointers.size === 2) {
        const [a, b] = [...pointers.values()];
        const d = Math.hypot(a[0] - b[0], a[1] - b[1]);
        if (pinch) sylva.app.zoom(Math.log(d / pinch) / -Math.log(0.9));
        pinch = d;
    }
});
const lift = (e) => {
    pointers.delete(e.pointerId);
    if (pointers.size < 2) pinch = null;
};
canvas.addEventListener('pointerup', lift);
canvas.addEventListener('pointercancel', lift);
canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const lines = e.deltaMode === 1 ? e.deltaY : e.deltaY / 100;
    if (sylva.app) sylva.app.zoom(-lines);
}, { passive: false });

// Keys held move the camera's target, as in the desktop viewer.
const held = new Set();
const typing = () => ['INPUT', 'SELECT', 'BUTTON'].includes(document.activeElement?.tagName);
window.addEventListener('keydown', (e) => { if (!typing()) held.add(e.code); });
window.addEventListener('keyup', (e) => held.delete(e.code));
window.addEventListener('blur', () => held.clear());
function travel(dt) {
    const axis = (plus, minus) => (held.has(plus) ? 1 : 0) - (held.has(minus) ? 1 : 0);
    const f = axis('KeyW', 'KeyS'), r = axis('KeyD', 'KeyA'), u = axis('KeyE', 'KeyQ');
    if (f || r || u) sylva.app.travel(f, r, u, dt);
}

// A scene change hands the app to the engine and back (it awaits the GPU's bake of the
// impostors); its outcome is kept in the app.
async function handOver(change) {
    const app = sylva.app;
    sylva.app = null;
    sylva.app = await change(app);
    const error = sylva.app.take_error();
    if (error) throw new Error(error);
    return sylva.app.take_message();
}

// Files: dropped on the page or opened; read by the command line's readers.
async function readFiles(files) {
    for (const file of files) {
        const text = await file.text();
        await busy(`reading ${file.name}`, () => handOver((app) => app.read_file(file.name, text)));
    }
}
window.addEventListener('dragover', (e) => e.preventDefault());
window.addEventListener('drop', (e) => {
    e.preventDefault();
    if (sylva.app && e.dataTransfer) readFiles([...e.dataTransfer.files]);
});
$('open').addEventListener('change', (e) => {
    if (sylva.app) readFiles([...e.target.files]).then(() => { e.target.value = ''; });
});

function bindPanel() {
    const applyLod = () => {
        sylva.app.set_lod($('lod-geometry').checked, $('lod-animation').checked);
        sylva.app.set_wind_gain(Number($('gain').value));
    };
    const change = (what, work) => busy(what, async () => {
        const done = await handOver(work);
        applyLod();
        return done;
    });
    $('scene').addEventListener('change', (e) => {
        const wind = $('wind').value;
        change(`growing scene ${e.target.value}`, (app) => app.set_scene(e.target.value, wind));
    });
    $('wind').addEventListener('change', (e) => {
        busy(`synthesising the ${e.target.value} wind`, () => sylva.app.set_wind(e.target.value));
    });
    $('gain').addEventListener('input', (e) => {
        const g = Number(e.target.value);
        $('gain-value').textContent = `×${g.toFixed(1)}`;
        sylva.app.set_wind_gain(g);
    });
    $('lod-geometry').addEventListener('change', applyLod);
    $('lod-animation').addEventListener('change', applyLod);
    for (const name of presets()) {
        const o = document.createElement('option');
        o.value = name;
        o.textContent = name.replace(/_/g, ' ');
        $('species').append(o);
    }
    $('show-species').addEventListener('click', () => {
        const name = $('species').value;
        change(`growing a ${name.replace(/_/g, ' ')}`, (app) => app.show_species(name));
    });
}

const figure = (n) => n.toLocaleString('en-US');
let last = null;
let fpsFrames = 0;
let fpsSince = 0;
function loop(t) {
    const app = sylva.app;
    if (app && !sylva.busy) {
        const dt = last === null ? 0 : Math.min((t - last) / 1000, 1);
        last = t;
        sizeCanvas();
        travel(dt);
        try {
            app.frame(dt);
        } catch (e) {
            showError(e);
        }
        sylva.frames += 1;
        if (sylva.firstFrameMs === null) sylva.firstFrameMs = performance.now();
        fpsFrames += 1;
        if (t - fpsSince >= 500) {
            sylva.fps = (1000 * fpsFrames) / (t - fpsSince);
            fpsFrames = 0;
            fpsSince = t;
            sylva.figures = {
                triangles: app.triangles(),
                drawn: app.drawn(),
                trees: app.trees(),
                simMs: app.sim_ms(),
                buildMs: app.build_ms(),
            };
            const f = sylva.figures;
            $('fig-fps').textContent = sylva.fps.toFixed(1);
            $('fig-triangles').textContent = figure(f.triangles);
            $('fig-trees').textContent = `${figure(f.drawn)} of ${figure(f.trees)}`;
            $('fig-sim').textContent = `${f.simMs.toFixed(1)} ms`;
            $('fig-build').textContent = `${f.buildMs.toFixed(1)} ms`;
        }
    } else {
        last = null;
    }
    requestAnimationFrame(loop);
}

async function main() {
    try {
        const started = performance.now();
        await init();
        sizeCanvas();
        // `?webgl2` in the address: WebGL2 even where the browser has WebGPU.
        const webgl2 = new URLSearchParams(location.search).has('webgl2');
        const app = await App.create(canvas, 'small', $('wind').value, webgl2);
        sylva.app = app;
        sylva.startMs = performance.now() - started;
        $('backend').textContent = `${app.backend()} · wind and trees made in the page`;
        bindPanel();
        requestAnimationFrame(loop);
    } catch (e) {
        $('backend').textContent = 'could not start';
        showError(e);
        console.error(`sylva: ${e && e.message ? e.message : e}`);
    }
}

main();
