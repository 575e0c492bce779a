// robodesign viewer: draws the scene data embedded in the page (robodesign.viewer.scene) with three.js.
// three.js and OrbitControls are inlined in the page as text (<script type="text/plain">) and imported
// from blob: URLs, so the page needs no network and no server.
const statusEl = document.getElementById('status');
function fail(msg) {
  statusEl.textContent = msg;
  statusEl.classList.add('error');
  document.body.dataset.viewerError = msg;
}
try {
  await main();
} catch (err) {
  console.error(err);
  fail('viewer error: ' + (err && err.message ? err.message : err));
}

async function main() {
  const text = (id) => document.getElementById(id).textContent;
  const data = JSON.parse(text('scene-data'));
  const threeURL = URL.createObjectURL(new Blob([text('three-src')], { type: 'text/javascript' }));
  const THREE = await import(threeURL);
  const orbitSrc = text('orbit-src').replace(/from\s*['"]three['"]/g, `from '${threeURL}'`);
  const { OrbitControls } = await import(URL.createObjectURL(new Blob([orbitSrc], { type: 'text/javascript' })));

  THREE.Object3D.DEFAULT_UP.set(0, 0, 1); // CoBRA: z up
  const viewport = document.getElementById('viewport');
  const canvas = document.getElementById('canvas');
  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ canvas, antialias: true, preserveDrawingBuffer: true });
  } catch (err) {
    fail('WebGL is not available in this browser: the 3-D view cannot be shown (plots and tables still are).');
    return;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf2f4f7);

  // ---------------------------------------------------------------- helpers
  function b64(str, Type) {
    const bin = atob(str);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }
  function mat4(p) {
    const m = new THREE.Matrix4();
    m.set(p[0][0], p[0][1], p[0][2], p[0][3], p[1][0], p[1][1], p[1][2], p[1][3],
          p[2][0], p[2][1], p[2][2], p[2][3], p[3][0], p[3][1], p[3][2], p[3][3]);
    return m;
  }
  function place(obj, pose) {
    obj.matrixAutoUpdate = false;
    obj.matrix.copy(mat4(pose));
    obj.matrixWorldNeedsUpdate = true;
    return obj;
  }
  const layers = {}; // name -> [objects]
  function addLayer(name, obj) { (layers[name] = layers[name] || []).push(obj); }

  const meshGeoms = {};
  function meshGeometry(id) {
    if (!meshGeoms[id]) {
      const rec = data.meshes[id];
      const g = new THREE.BufferGeometry();
      g.setAttribute('position', new THREE.BufferAttribute(b64(rec.vertices, Float32Array), 3));
      g.setIndex(new THREE.BufferAttribute(b64(rec.indices, rec.index_type === 'uint16' ? Uint16Array : Uint32Array), 1));
      g.computeVertexNormals();
      g.computeBoundingSphere();
      meshGeoms[id] = g;
    }
    return meshGeoms[id];
  }
  function material(g, flat) {
    const transparent = g.opacity < 1;
    return new THREE.MeshStandardMaterial({
      color: new THREE.Color(g.color), metalness: 0.1, roughness: 0.65, transparent, opacity: g.opacity,
      depthWrite: !transparent, side: (flat || transparent) ? THREE.DoubleSide : THREE.FrontSide, flatShading: !!flat,
    });
  }
  const axisColors = [0xd62728, 0x2ca02c, 0x1f77b4];
  function triad(size) {
    const grp = new THREE.Group();
    const r = size * 0.045;
    for (let a = 0; a < 3; a++) {
      const mat = new THREE.MeshBasicMaterial({ color: axisColors[a] });
      const shaft = new THREE.Mesh(new THREE.CylinderGeometry(r, r, size * 0.8, 10), mat);
      shaft.position.y = size * 0.4;
      const tip = new THREE.Mesh(new THREE.ConeGeometry(r * 2.2, size * 0.2, 12), mat);
      tip.position.y = size * 0.9;
      const arm = new THREE.Group();
      arm.add(shaft, tip);
      if (a === 0) arm.rotation.z = -Math.PI / 2; // y -> x
      if (a === 2) arm.rotation.x = Math.PI / 2; // y -> z
      grp.add(arm);
    }
    return grp;
  }
  function geometryObject(g) {
    let geo = null, flat = false;
    switch (g.type) {
      case 'box': geo = new THREE.BoxGeometry(g.size[0], g.size[1], g.size[2]); break;
      case 'cylinder': geo = new THREE.CylinderGeometry(g.radius, g.radius, g.length, 40).rotateX(Math.PI / 2); break;
      case 'sphere': geo = new THREE.SphereGeometry(g.radius, 32, 16); break;
      case 'mesh': geo = meshGeometry(g.mesh); flat = true; break;
      case 'triad': return place(triad(g.size), g.pose);
      case 'line': {
        const lg = new THREE.BufferGeometry().setFromPoints(g.points.map((p) => new THREE.Vector3(p[0], p[1], p[2])));
        return place(new THREE.Line(lg, new THREE.LineBasicMaterial({ color: new THREE.Color(g.color) })), g.pose);
      }
      default: return null;
    }
    if (g.role === 'tolerance') {
      const grp = new THREE.Group();
      const fill = new THREE.Mesh(geo, material({ color: g.color, opacity: g.wireframe ? g.opacity * 0.4 : g.opacity }));
      fill.renderOrder = 2;
      const edges = new THREE.LineSegments(new THREE.EdgesGeometry(geo, 20),
        new THREE.LineBasicMaterial({ color: new THREE.Color(g.color), transparent: true, opacity: 0.8 }));
      grp.add(fill, edges);
      return place(grp, g.pose);
    }
    const m = new THREE.Mesh(geo, material(g, flat));
    if (g.opacity < 1) m.renderOrder = 1;
    return place(m, g.pose);
  }

  // ---------------------------------------------------------------- nodes
  const nodeById = {};
  const labelEls = [];
  const labelsDiv = document.getElementById('labels');
  for (const n of data.nodes) {
    const grp = new THREE.Group();
    grp.name = n.id;
    place(grp, n.pose || [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]);
    for (const g of n.geometries) {
      const obj = geometryObject(g);
      if (!obj) continue;
      grp.add(obj);
      if (g.role === 'collision') addLayer('collision', obj);
      else if (g.role === 'tolerance') addLayer('tolerance', obj);
    }
    scene.add(grp);
    nodeById[n.id] = grp;
    const layer = { robot: 'robot', tcp: 'robot', base: 'robot', obstacle: 'obstacle', goal: 'goal', placement: 'goal' }[n.group] || n.group;
    addLayer(layer, grp);
    if (n.label) {
      const el = document.createElement('div');
      el.className = 'label';
      el.textContent = n.label;
      el.title = n.name;
      labelsDiv.appendChild(el);
      const at = n.label_at ? new THREE.Vector3(...n.label_at) : null;
      labelEls.push({ el, grp, at });
    }
  }
  for (const obj of layers.collision || []) obj.visible = false;

  if (data.paths && data.paths.tcp_b64) {
    const pts = b64(data.paths.tcp_b64, Float32Array);
    const lg = new THREE.BufferGeometry();
    lg.setAttribute('position', new THREE.BufferAttribute(pts, 3));
    const line = new THREE.Line(lg, new THREE.LineBasicMaterial({ color: 0xff7f0e }));
    scene.add(line);
    addLayer('path', line);
  }

  // ---------------------------------------------------------------- lights, grid, camera
  const bmin = new THREE.Vector3(...data.bounds.min), bmax = new THREE.Vector3(...data.bounds.max);
  const center = bmin.clone().add(bmax).multiplyScalar(0.5);
  const radius = Math.max(0.3, bmax.clone().sub(bmin).length() / 2);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x8090a0, 2.2));
  const sun = new THREE.DirectionalLight(0xffffff, 2.2);
  sun.position.copy(center).add(new THREE.Vector3(2, -3, 5).multiplyScalar(radius));
  scene.add(sun);
  const fill = new THREE.DirectionalLight(0xffffff, 0.8);
  fill.position.copy(center).add(new THREE.Vector3(-3, 2, 1).multiplyScalar(radius));
  scene.add(fill);
  const gridSize = Math.max(1, Math.ceil(2.5 * radius));
  const grid = new THREE.GridHelper(gridSize * 2, gridSize * 10, 0x9aa3ad, 0xd0d5db);
  grid.rotation.x = Math.PI / 2;
  grid.position.set(Math.round(center.x), Math.round(center.y), 0);
  scene.add(grid);
  addLayer('grid', grid);
  const world = triad(0.1);
  scene.add(world);
  addLayer('grid', world);

  const camera = new THREE.PerspectiveCamera(40, 1, Math.max(radius / 500, 0.001), radius * 200);
  const dir = new THREE.Vector3(1.2, -1.6, 1.0).normalize();
  const dist = radius / Math.sin((40 / 2) * Math.PI / 180) * 0.9;
  camera.position.copy(center).addScaledVector(dir, dist);
  const controls = new OrbitControls(camera, renderer.domElement);
  controls.target.copy(center);
  controls.update();
  let dirty = true;
  controls.addEventListener('change', () => { dirty = true; });

  function renderNow() {
    scene.updateMatrixWorld();
    renderer.render(scene, camera);
    updateLabels();
    dirty = false;
  }
  function resize() {
    const w = viewport.clientWidth, h = viewport.clientHeight;
    renderer.setSize(w, h, false); // clears the canvas: draw again at once, not at the next frame
    camera.aspect = w / Math.max(h, 1);
    camera.updateProjectionMatrix();
    renderNow();
  }

  // ---------------------------------------------------------------- animation
  const anim = data.animation;
  const slider = document.getElementById('slider');
  const playBtn = document.getElementById('play');
  const timeEl = document.getElementById('time');
  const speedSel = document.getElementById('speed');
  const loopBox = document.getElementById('loop');
  let frame = 0, simTime = 0, playing = false;
  let poses = null, animNodes = [], T = [];
  const goalAtFrame = {};
  if (anim) {
    poses = b64(anim.poses_b64, Float32Array);
    animNodes = anim.nodes.map((id) => nodeById[id]);
    T = anim.t;
    for (const [gid, j] of Object.entries(anim.goal_frames || {})) (goalAtFrame[j] = goalAtFrame[j] || []).push(gid);
    slider.max = String(T.length - 1);
    simTime = T[0];
  } else {
    document.getElementById('controls').classList.add('static');
  }
  const m0 = new THREE.Matrix4(), m1 = new THREE.Matrix4();
  const p0 = new THREE.Vector3(), p1 = new THREE.Vector3(), s0 = new THREE.Vector3();
  const q0 = new THREE.Quaternion(), q1 = new THREE.Quaternion();
  function readPose(m, j, i) {
    const o = (j * animNodes.length + i) * 12, p = poses;
    m.set(p[o], p[o + 1], p[o + 2], p[o + 3], p[o + 4], p[o + 5], p[o + 6], p[o + 7],
          p[o + 8], p[o + 9], p[o + 10], p[o + 11], 0, 0, 0, 1);
  }
  function frameAt(t) { // last frame with T[j] <= t
    let lo = 0, hi = T.length - 1;
    if (t >= T[hi]) return hi;
    while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (T[mid] <= t) lo = mid; else hi = mid; }
    return lo;
  }
  function showTime(t) {
    const j = frameAt(t);
    const alpha = j < T.length - 1 ? (t - T[j]) / (T[j + 1] - T[j]) : 0;
    for (let i = 0; i < animNodes.length; i++) {
      const node = animNodes[i];
      readPose(node.matrix, j, i);
      if (alpha > 1e-6) {
        node.matrix.decompose(p0, q0, s0);
        readPose(m1, j + 1, i);
        m1.decompose(p1, q1, s0);
        p0.lerp(p1, alpha);
        q0.slerp(q1, alpha);
        node.matrix.compose(p0, q0, s0.set(1, 1, 1));
      }
      node.matrixWorldNeedsUpdate = true;
    }
    frame = j;
    slider.value = String(j);
    const goals = alpha <= 1e-6 && goalAtFrame[j] ? '  ·  goal ' + goalAtFrame[j].join(', ') : '';
    timeEl.textContent = `t = ${t.toFixed(3)} s / ${T[T.length - 1].toFixed(3)} s  ·  frame ${j + 1}/${T.length}${goals}`;
    dirty = true;
  }
  function setPlaying(on) {
    playing = on && !!anim;
    playBtn.textContent = playing ? '❚❚ Pause' : '▶ Play';
    playBtn.setAttribute('aria-pressed', String(playing));
  }
  function setFrame(j) {
    if (!anim) return;
    setPlaying(false);
    simTime = T[Math.max(0, Math.min(T.length - 1, j))];
    showTime(simTime);
  }
  if (anim) {
    // open at a given instant: page.html#t=1.5 or #frame=40 (add &play to start playing)
    const hash = new URLSearchParams(location.hash.replace(/^#/, ''));
    if (hash.has('frame')) simTime = T[Math.max(0, Math.min(T.length - 1, parseInt(hash.get('frame'), 10) || 0))];
    else if (hash.has('t')) simTime = Math.max(T[0], Math.min(T[T.length - 1], parseFloat(hash.get('t')) || 0));
    showTime(simTime);
    if (hash.has('play')) setPlaying(true);
    playBtn.addEventListener('click', () => {
      if (!playing && simTime >= T[T.length - 1]) simTime = T[0];
      setPlaying(!playing);
    });
    slider.addEventListener('input', () => setFrame(parseInt(slider.value, 10)));
    document.addEventListener('keydown', (e) => {
      if (e.target && (e.target.tagName === 'INPUT' && e.target.type !== 'range' || e.target.tagName === 'SELECT')) return;
      if (e.code === 'Space') { e.preventDefault(); playBtn.click(); }
      else if (e.key === 'ArrowRight' || e.key === '.') { e.preventDefault(); setFrame(frame + 1); }
      else if (e.key === 'ArrowLeft' || e.key === ',') { e.preventDefault(); setFrame(frame - 1); }
    });
    for (const b of document.querySelectorAll('[data-frame]')) {
      b.addEventListener('click', () => setFrame(parseInt(b.dataset.frame, 10)));
    }
  }

  // ---------------------------------------------------------------- layer toggles
  for (const box of document.querySelectorAll('input[data-layer]')) {
    const apply = () => { for (const o of layers[box.dataset.layer] || []) o.visible = box.checked; dirty = true; };
    box.addEventListener('change', apply);
    apply();
    if (!layers[box.dataset.layer]) box.closest('label').hidden = true;
  }
  document.getElementById('reset-view').addEventListener('click', () => {
    camera.position.copy(center).addScaledVector(dir, dist);
    controls.target.copy(center);
    controls.update();
  });

  // ---------------------------------------------------------------- render loop
  const v = new THREE.Vector3();
  function updateLabels() {
    const w = viewport.clientWidth, h = viewport.clientHeight;
    const showGoals = (layers.goal || []).some((o) => o.visible);
    for (const L of labelEls) {
      if (L.at) v.copy(L.at); else v.setFromMatrixPosition(L.grp.matrixWorld);
      v.project(camera);
      const visible = showGoals && v.z < 1 && Math.abs(v.x) <= 1.05 && Math.abs(v.y) <= 1.05;
      L.el.style.display = visible ? '' : 'none';
      if (visible) L.el.style.transform = `translate(${((v.x + 1) / 2 * w).toFixed(1)}px, ${((1 - v.y) / 2 * h).toFixed(1)}px)`;
    }
  }
  let last = performance.now();
  function tick(now) {
    const dt = Math.min(0.1, (now - last) / 1000);
    last = now;
    if (playing) {
      simTime += dt * parseFloat(speedSel.value);
      const tEnd = T[T.length - 1];
      if (simTime >= tEnd) {
        if (loopBox.checked) simTime = T[0] + ((simTime - T[0]) % Math.max(tEnd - T[0], 1e-9));
        else { simTime = tEnd; setPlaying(false); }
      }
      showTime(simTime);
    }
    if (dirty) renderNow();
    requestAnimationFrame(tick);
  }
  resize();
  new ResizeObserver(resize).observe(viewport);
  requestAnimationFrame(tick);

  statusEl.textContent = anim ? `${T.length} frames, ${animNodes.length} moving parts` : 'static scene';
  window.robodesignViewer = { THREE, scene, camera, controls, renderer, data, setFrame, showTime,
    play: () => setPlaying(true), pause: () => setPlaying(false), get frame() { return frame; } };
  document.body.dataset.viewerReady = '1';
}
