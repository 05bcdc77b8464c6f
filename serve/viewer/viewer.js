// cwloc-serve's map viewer: draws an index's 3D points and cameras (GET /v1/map), localizes
// dropped photos (POST /v1/localize; several photos: a session, POST /v1/sessions) and draws
// their poses. Plain JavaScript on three.js r111's global build (THREE, THREE.OrbitControls);
// no build step and nothing fetched from elsewhere, so it works offline.
//
// Frames: everything is drawn in the index's model frame. COLMAP's camera frame is x right,
// y down, z forward, and poses are cam_from_world; the model's "up" is unknown, so it is taken
// as minus the mean of the cameras' y axes (people hold cameras roughly level).
//
// For tests: after each result, window.cwlocLastResult is the record, document.body.dataset.state
// is "posed", "failed" or "error", and #pose-center holds the centre as "x y z"; once the points
// are drawn, document.body.dataset.map is "loaded".
'use strict';

(function () {
  const { percentile, worldFromCam, sceneFrame, frustumLines, focalsOf, symmetricEigen3 } = CwlocGeometry;
  const MAX_POINTS = 100000;  // asked of /v1/map: enough to see the structure, light to draw
  const CHI2_3D_95 = 7.815;   // the chi-square quantile for 3 degrees of freedom at 95 %
  const TOKEN_KEY = 'cwloc.token';
  const COLORS = {
    background: 0x101317,
    mapCamera: 0x9fb3c8,
    pose: 0xff7a1a,         // a single photo's pose, and a session's tracked frames
    relocalized: 0xff4fd8,  // a session's frames localized afresh (not tracked)
    trajectory: 0xffb36b,
    ellipsoid: 0x4ad8ff,
  };
  // Points take the model's colours when the index has them (cwloc-index build --point-colors);
  // otherwise their height along the estimated up direction (blue low, pale yellow high), which
  // shows a building's or a street's structure best.
  const RAMP = ['#2b4ab0', '#2f8fd0', '#3cc4b4', '#9ad96b', '#f2ec8a'];

  const $ = (id) => document.getElementById(id);
  const ui = {
    view: $('view'), indexInfo: $('index-info'), indexChoice: $('index-choice'),
    indexSelect: $('index-select'), token: $('token'), input: $('photo-input'),
    status: $('status'), result: $('result'), legendRamp: $('legend-ramp'), legend: $('legend-height'),
  };
  ui.legendRamp.style.background = `linear-gradient(to right, ${RAMP.join(', ')})`;

  // ---------------------------------------------------------------- small helpers

  // Builds an element; children are nodes or text (never parsed as HTML: names come from users).
  function el(tag, attributes, ...children) {
    const node = document.createElement(tag);
    for (const [key, value] of Object.entries(attributes || {})) {
      if (key === 'class') node.className = value;
      else if (key.startsWith('on')) node.addEventListener(key.slice(2), value);
      else node.setAttribute(key, value);
    }
    for (const child of children.flat()) {
      if (child !== null && child !== undefined && child !== false) {
        node.append(child instanceof Node ? child : String(child));
      }
    }
    return node;
  }

  const fixed = (x, digits) => (typeof x === 'number' && isFinite(x) ? x.toFixed(digits) : '–');
  const grouped = (n) => Number(n).toLocaleString('en-US');

  function setStatus(text, isError) {
    ui.status.textContent = text;
    ui.status.classList.toggle('error', Boolean(isError));
  }

  function setState(state) {
    document.body.dataset.state = state;
  }

  // localStorage throws in some privacy modes; the token then lasts for the page only.
  function loadToken() {
    try { return localStorage.getItem(TOKEN_KEY) || ''; } catch (e) { return ''; }
  }
  function saveToken(token) {
    try {
      if (token) localStorage.setItem(TOKEN_KEY, token); else localStorage.removeItem(TOKEN_KEY);
    } catch (e) { /* kept in the field only */ }
  }

  // ---------------------------------------------------------------- the server's API

  // A JSON call; refusals throw an Error with the server's message and .status.
  async function api(path, { method = 'GET', body = null, timeoutMs = 30000 } = {}) {
    const headers = {};
    const token = ui.token.value.trim();
    if (token) headers.Authorization = 'Bearer ' + token;
    const abort = new AbortController();
    const timer = setTimeout(() => abort.abort(), timeoutMs);
    try {
      const res = await fetch(path, { method, body, headers, signal: abort.signal });
      if (res.status === 204) return null;
      const text = await res.text();
      let json = null;
      try { json = JSON.parse(text); } catch (e) { /* reported below */ }
      if (!res.ok) {
        const error = new Error(`${res.status}: ${json && json.error ? json.error : res.statusText}`);
        error.status = res.status;
        throw error;
      }
      if (json === null) throw new Error(`${method} ${path}: the answer is not JSON`);
      return json;
    } catch (e) {
      if (abort.signal.aborted) throw new Error(`${method} ${path}: no answer within ${timeoutMs / 1000} s`);
      throw e;
    } finally {
      clearTimeout(timer);
    }
  }

  function photoForm(file) {
    const form = new FormData();
    form.append('image', file, file.name);
    return form;
  }

  // A photo's localization can wait behind other queries: allow minutes, not seconds.
  const PHOTO_TIMEOUT_MS = 180000;

  // ---------------------------------------------------------------- three.js scene

  let renderer;
  try {
    renderer = new THREE.WebGLRenderer({ antialias: true });
  } catch (e) {
    setStatus('This browser cannot draw WebGL: ' + e.message, true);
    document.body.dataset.map = 'error';
    throw e;
  }
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.setSize(window.innerWidth, window.innerHeight);
  ui.view.appendChild(renderer.domElement);

  const scene = new THREE.Scene();
  scene.background = new THREE.Color(COLORS.background);
  const camera = new THREE.PerspectiveCamera(50, window.innerWidth / window.innerHeight, 0.01, 1000);
  const mapGroup = new THREE.Group();     // the index: points and cameras
  const resultGroup = new THREE.Group();  // the dropped photos' poses
  scene.add(mapGroup, resultGroup);
  let controls = null;
  let points = null;  // the THREE.Points, for double-click picking
  renderer.render(scene, camera);  // the background, until a map comes

  // The scene's robust frame: centre, extent (a typical distance from it), up, viewing direction.
  let frame = {
    center: new THREE.Vector3(), extent: 1, up: new THREE.Vector3(0, -1, 0),
    viewDir: new THREE.Vector3(0, 0, 1), home: new THREE.Vector3(), halfSizes: [1, 1, 1],
  };

  // Renders now: tests look at the page as soon as the state says a result is drawn.
  function render() {
    // The near plane follows the zoom, so that the (millimetre) ellipsoid can be looked at closely.
    if (controls) {
      const distance = camera.position.distanceTo(controls.target);
      camera.near = Math.max(distance * 1e-3, 1e-6);
      camera.far = Math.max(distance, frame.extent) * 200;
      camera.updateProjectionMatrix();
    }
    renderer.render(scene, camera);
  }

  window.addEventListener('resize', () => {
    camera.aspect = window.innerWidth / window.innerHeight;
    camera.updateProjectionMatrix();
    renderer.setSize(window.innerWidth, window.innerHeight);
    render();
  });

  function disposeTree(group) {
    for (const child of [...group.children]) {
      group.remove(child);
      child.traverse((node) => {
        if (node.geometry) node.geometry.dispose();
        if (node.material) {
          if (node.material.map) node.material.map.dispose();
          node.material.dispose();
        }
      });
    }
  }

  // Colours along RAMP, t in [0, 1].
  const rampColors = RAMP.map((hex) => new THREE.Color(hex));
  function rampColor(t, out) {
    const scaled = Math.min(Math.max(t, 0), 1) * (rampColors.length - 1);
    const i = Math.min(Math.floor(scaled), rampColors.length - 2);
    return out.copy(rampColors[i]).lerp(rampColors[i + 1], scaled - i);
  }

  // The index's cameras as small frusta, all in one geometry, each with its image's proportions
  // and field of view.
  function mapCameraFrusta(cameras, size) {
    const shapes = cameras.map((c) => {
      const [fx, fy] = focalsOf(c.camera);
      const hw = (c.camera.width / 2) / (fx || c.camera.width);
      const hh = (c.camera.height / 2) / (fy || c.camera.width);
      return frustumLines(hw, hh, false).map((p) => new THREE.Vector3(...p).multiplyScalar(size));
    });
    const positions = new Float32Array(shapes.reduce((n, s) => n + s.length * 3, 0));
    let k = 0;
    const v = new THREE.Vector3();
    for (const [i, c] of cameras.entries()) {
      for (const p of shapes[i]) {
        v.copy(p).applyQuaternion(c.rotation).add(c.center);
        positions[k++] = v.x; positions[k++] = v.y; positions[k++] = v.z;
      }
    }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(positions, 3));
    return new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ color: COLORS.mapCamera }));
  }

  function pointCloud(xyz, rgb) {
    const n = xyz.length / 3;
    if (rgb && rgb.length === xyz.length) {
      ui.legend.hidden = true;  // the height ramp does not apply
      return pointsObject(xyz, Float32Array.from(rgb, (c) => c / 255));
    }
    ui.legend.hidden = false;
    const heights = new Float64Array(n);
    for (let i = 0; i < n; i++) {
      heights[i] = (xyz[3 * i] - frame.center.x) * frame.up.x + (xyz[3 * i + 1] - frame.center.y) * frame.up.y +
                   (xyz[3 * i + 2] - frame.center.z) * frame.up.z;
    }
    const low = percentile(heights, 0.02);
    const high = percentile(heights, 0.98);
    const colors = new Float32Array(3 * n);
    const color = new THREE.Color();
    for (let i = 0; i < n; i++) {
      rampColor((heights[i] - low) / (high - low || 1), color);
      colors[3 * i] = color.r; colors[3 * i + 1] = color.g; colors[3 * i + 2] = color.b;
    }
    return pointsObject(xyz, colors);
  }

  function pointsObject(xyz, colors) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute('position', new THREE.BufferAttribute(Float32Array.from(xyz), 3));
    geometry.setAttribute('color', new THREE.BufferAttribute(colors, 3));
    // Sized in model units, so that points grow as one zooms in.
    const material = new THREE.PointsMaterial({
      size: frame.extent * 0.011, sizeAttenuation: true, vertexColors: THREE.VertexColors,
    });
    return new THREE.Points(geometry, material);
  }

  function makeControls() {
    if (controls) controls.dispose();
    camera.up.copy(frame.up);  // OrbitControls keeps camera.up up; it reads it when made
    controls = new THREE.OrbitControls(camera, renderer.domElement);
    controls.screenSpacePanning = true;
    controls.addEventListener('change', render);
  }

  // Back from the scene along the photographers' direction and above it, far enough that the
  // home box (most points, all cameras) fills the window.
  const ELEVATION = 0.35;  // radians looking down (20 degrees)
  function showAll() {
    const [halfRight, halfUp, halfForward] = frame.halfSizes;
    const tanV = Math.tan((camera.fov * Math.PI / 180) / 2);
    const tanH = tanV * camera.aspect;
    // The box's extent across the screen's vertical, seen from ELEVATION above.
    const halfScreenUp = halfUp * Math.cos(ELEVATION) + halfForward * Math.sin(ELEVATION);
    const halfDepth = halfUp * Math.sin(ELEVATION) + halfForward * Math.cos(ELEVATION);
    const distance = 0.8 * Math.max(halfRight / tanH, halfScreenUp / tanV) + halfDepth;
    const back = frame.viewDir.clone().multiplyScalar(-Math.cos(ELEVATION)).addScaledVector(frame.up, Math.sin(ELEVATION));
    // Aimed a little above the box's middle: the scene sits lower, clear of the panels at the top.
    const target = frame.home.clone().addScaledVector(frame.up, 0.2 * halfScreenUp);
    camera.position.copy(target).addScaledVector(back, distance);
    controls.target.copy(target);
    controls.update();
    render();
  }

  // Orbit around a point: the camera keeps its direction and comes to `distance`.
  function focusOn(point, distance) {
    const direction = camera.position.clone().sub(controls.target).normalize();
    controls.target.copy(point);
    camera.position.copy(point).addScaledVector(direction, distance);
    controls.update();
    render();
  }

  // Double-click on a point: orbit around it.
  renderer.domElement.addEventListener('dblclick', (event) => {
    if (!points || !controls) return;
    const mouse = new THREE.Vector2(
      (event.clientX / window.innerWidth) * 2 - 1, -(event.clientY / window.innerHeight) * 2 + 1);
    const raycaster = new THREE.Raycaster();
    raycaster.params.Points.threshold = frame.extent * 0.01;
    raycaster.setFromCamera(mouse, camera);
    const hit = raycaster.intersectObject(points)[0];
    if (hit) focusOn(hit.point, camera.position.distanceTo(controls.target));
  });

  // ---------------------------------------------------------------- the index

  let indexName = '';
  let indexes = [];  // /v1/info's
  let busy = false;  // one photo or session at a time

  async function loadInfo() {
    document.body.dataset.map = 'loading';
    setStatus('asking the server for its indexes…');
    let info;
    try {
      info = await api('/v1/info');
    } catch (e) {
      showApiError(e);
      document.body.dataset.map = 'error';
      return;
    }
    ui.token.classList.remove('needed');
    indexes = info.indexes;
    ui.indexSelect.replaceChildren(...info.indexes.map((index) =>
      el('option', { value: index.name }, `${index.name} (${grouped(index.images)} images)`)));
    ui.indexChoice.hidden = info.indexes.length < 2;
    const wanted = info.indexes.some((index) => index.name === indexName) ? indexName : info.default_index;
    ui.indexSelect.value = wanted;
    await loadMap(wanted, info.indexes.find((index) => index.name === wanted));
  }

  async function loadMap(name, indexInfo) {
    indexName = name;
    document.body.dataset.map = 'loading';
    disposeTree(mapGroup);
    clearResults();
    points = null;
    setStatus(`loading the map of '${name}'…`);
    let map;
    try {
      map = await api(`/v1/map?index=${encodeURIComponent(name)}&max_points=${MAX_POINTS}`, { timeoutMs: 60000 });
    } catch (e) {
      showApiError(e);
      document.body.dataset.map = 'error';
      return;
    }
    if (name !== indexName) return;  // another index was chosen meanwhile
    const cameras = map.cameras.map((c) => ({
      name: c.name, rotation: worldFromCam(c.rotation), center: new THREE.Vector3(...c.center),
      camera: c.camera,
    }));
    frame = sceneFrame(map.points, cameras);
    points = pointCloud(map.points, map.colors);
    mapGroup.add(points, mapCameraFrusta(cameras, frame.extent * 0.06));
    makeControls();
    showAll();

    const shown = map.points.length / 3;
    ui.indexInfo.textContent = `${name}: ${grouped(cameras.length)} cameras, ` +
      (shown === map.num_points ? `${grouped(shown)} points` : `${grouped(shown)} of ${grouped(map.num_points)} points`) +
      (indexInfo && indexInfo.georeferenced ? ', georeferenced' : '');
    setStatus('');
    document.body.dataset.map = 'loaded';
  }

  function showApiError(e) {
    setStatus(e.message, true);
    // A 401 means the token is missing or wrong: point at the field.
    if (e.status === 401) {
      ui.token.classList.add('needed');
      setStatus(e.message + '\nEnter the token above.', true);
    }
  }

  ui.indexSelect.addEventListener('change', () => {
    if (busy) {  // the photos in flight belong to this map
      ui.indexSelect.value = indexName;
      setStatus('still busy with the last photos; choose the index when they are done');
      return;
    }
    loadMap(ui.indexSelect.value, indexes.find((index) => index.name === ui.indexSelect.value));
  });

  ui.token.value = loadToken();
  ui.token.addEventListener('change', () => {
    saveToken(ui.token.value.trim());
    loadInfo();
  });

  // ---------------------------------------------------------------- poses

  const results = [];  // what has been drawn: {record, object}
  let trajectory = null;

  function clearResults() {
    disposeTree(resultGroup);
    results.length = 0;
    trajectory = null;
    ui.result.hidden = true;
    ui.result.replaceChildren();
  }

  // The photo as a small texture for the frustum's image plane. The server reads pixels as
  // stored (it ignores EXIF orientation); when the browser's upright image has other
  // proportions, the plane stays plain rather than show the photo turned.
  function photoTexture(file, width, height) {
    return new Promise((resolve) => {
      if (!file) return resolve(null);
      const url = URL.createObjectURL(file);
      const image = new Image();
      image.onload = () => {
        URL.revokeObjectURL(url);
        const sameShape = Math.abs(image.naturalWidth * height - image.naturalHeight * width) <= 0.02 * width * height;
        if (!sameShape) return resolve(null);
        const canvas = document.createElement('canvas');
        canvas.width = 512;
        canvas.height = Math.max(1, Math.round(512 * height / width));
        canvas.getContext('2d').drawImage(image, 0, 0, canvas.width, canvas.height);
        const texture = new THREE.CanvasTexture(canvas);
        texture.minFilter = THREE.LinearFilter;  // no mipmaps: WebGL 1 wants them power-of-two
        texture.generateMipmaps = false;
        resolve(texture);
      };
      image.onerror = () => { URL.revokeObjectURL(url); resolve(null); };
      image.src = url;
    });
  }

  // A localized photo: its frustum (image proportions and focal from the record), the photo on
  // its image plane, and its 95 % position ellipsoid.
  function poseObject(record, texture, color) {
    const group = new THREE.Group();
    const width = record.camera.width;
    const height = record.camera.height;
    const [fx, fy] = focalsOf(record.camera);
    const hw = (width / 2) / (fx || width);
    const hh = (height / 2) / (fy || width);

    const frustum = new THREE.Group();
    frustum.position.set(...record.pose.center);
    frustum.quaternion.copy(worldFromCam(record.pose.qvec));
    // Some four times a map camera's frustum: the query stands out among them.
    const depth = frame.extent * 0.15 / Math.max(hw, 0.2);
    frustum.scale.setScalar(depth);
    const lines = new THREE.BufferGeometry().setFromPoints(
      frustumLines(hw, hh, true).map((p) => new THREE.Vector3(...p)));
    frustum.add(new THREE.LineSegments(lines, new THREE.LineBasicMaterial({ color })));

    // The image plane at depth 1: u to the right (+x), v down (+y); the texture's v is up.
    const plane = new THREE.BufferGeometry();
    plane.setAttribute('position', new THREE.Float32BufferAttribute([
      -hw, -hh, 1, hw, -hh, 1, hw, hh, 1, -hw, -hh, 1, hw, hh, 1, -hw, hh, 1], 3));
    plane.setAttribute('uv', new THREE.Float32BufferAttribute([0, 1, 1, 1, 1, 0, 0, 1, 1, 0, 0, 0], 2));
    const planeMaterial = texture
      ? new THREE.MeshBasicMaterial({ map: texture, side: THREE.DoubleSide, transparent: true, opacity: 0.9 })
      : new THREE.MeshBasicMaterial({ color, side: THREE.DoubleSide, transparent: true, opacity: 0.25, depthWrite: false });
    frustum.add(new THREE.Mesh(plane, planeMaterial));
    group.add(frustum);

    const ellipsoid = ellipsoidObject(record);
    if (ellipsoid) group.add(ellipsoid);
    return group;
  }

  // The 95 % region of the camera centre: covariance.pose is over (rotation vector, centre), so
  // its bottom-right 3x3 block is the centre's covariance; radii sqrt(chi2 * eigenvalue).
  function ellipsoidObject(record) {
    const pose = record.covariance && record.covariance.pose;
    if (!Array.isArray(pose) || pose.length !== 6) return null;
    const block = [3, 4, 5].map((i) => [pose[i][3], pose[i][4], pose[i][5]]);
    const { values, vectors } = symmetricEigen3(block);
    const radii = values.map((value) => Math.sqrt(CHI2_3D_95 * Math.max(value, 0)));
    if (!radii.every(isFinite) || Math.max(...radii) === 0) return null;
    const axis = (j) => new THREE.Vector3(vectors[0][j], vectors[1][j], vectors[2][j]);
    const x = axis(0), y = axis(1);
    const z = new THREE.Vector3().crossVectors(x, y);  // a rotation, not a reflection
    const group = new THREE.Group();
    group.matrixAutoUpdate = false;
    group.matrix.makeBasis(x, y, z)
      .multiply(new THREE.Matrix4().makeScale(...radii.map((r) => Math.max(r, 1e-12))))
      .setPosition(new THREE.Vector3(...record.pose.center));
    group.add(new THREE.Mesh(new THREE.SphereBufferGeometry(1, 24, 16), new THREE.MeshBasicMaterial({
      color: COLORS.ellipsoid, transparent: true, opacity: 0.3, depthWrite: false })));
    // Its three principal ellipses, which show its shape from any side.
    const circle = [];
    for (let i = 0; i <= 64; i++) circle.push(new THREE.Vector3(Math.cos(i * Math.PI / 32), Math.sin(i * Math.PI / 32), 0));
    const material = new THREE.LineBasicMaterial({ color: COLORS.ellipsoid });
    for (const rotation of [new THREE.Euler(0, 0, 0), new THREE.Euler(Math.PI / 2, 0, 0), new THREE.Euler(0, Math.PI / 2, 0)]) {
      const loop = new THREE.Line(new THREE.BufferGeometry().setFromPoints(circle), material);
      loop.rotation.copy(rotation);
      group.add(loop);
    }
    group.userData.radii = radii;
    return group;
  }

  // Draws a record; returns whether it had a pose.
  async function drawRecord(record, file) {
    const posed = Boolean(record.success && record.pose && record.camera);
    let object = null;
    if (posed) {
      const mode = record.tracking && record.tracking.mode;
      const color = mode === 'relocalized' ? COLORS.relocalized : COLORS.pose;
      const texture = await photoTexture(file, record.camera.width, record.camera.height);
      object = poseObject(record, texture, color);
      resultGroup.add(object);
    }
    results.push({ record, object });
    updateTrajectory();
    render();
    return posed;
  }

  // The line through the centres of the frames that have a pose, in the order they were sent.
  function updateTrajectory() {
    const centres = results.filter((r) => r.object).map((r) => new THREE.Vector3(...r.record.pose.center));
    if (trajectory) {
      resultGroup.remove(trajectory);
      trajectory.geometry.dispose();
      trajectory = null;
    }
    if (centres.length < 2) return;
    trajectory = new THREE.Line(new THREE.BufferGeometry().setFromPoints(centres),
      new THREE.LineBasicMaterial({ color: COLORS.trajectory }));
    resultGroup.add(trajectory);
  }

  // Publishes a result for tests and scripts (see the top of this file).
  function publish(record) {
    window.cwlocLastResult = record;
    setState(record.success ? 'posed' : 'failed');
  }

  // ---------------------------------------------------------------- the result panel

  // compactTimes: per-stage times folded away (a session's panel lists frames above them).
  function recordDetails(record, compactTimes) {
    const rows = [];
    const row = (label, value, attributes) => rows.push(el('tr', null, el('td', null, label), el('td', attributes || null, value)));
    if (record.success) {
      row('result', el('span', { class: 'ok' }, 'localized'));
    } else {
      row('result', el('span', { class: 'bad' }, 'not localized'));
      row('why', record.failure_reason || '–');
    }
    if (record.tracking) row('tracking', record.tracking.mode);
    if (typeof record.num_inliers === 'number') {
      row('inliers', el('span', { id: 'num-inliers' }, String(record.num_inliers)));
      if (typeof record.inlier_ratio === 'number') row('inlier ratio', `${(100 * record.inlier_ratio).toFixed(1)} %`);
    }
    if (record.success && record.pose) {
      row('centre', record.pose.center.map((x) => fixed(x, 6)).join(' '), { id: 'pose-center', class: 'mono' });
      const radius = record.covariance && record.covariance.position_radius95;
      if (typeof radius === 'number') row('95 % radius', `${radius.toPrecision(3)} model units`);
    }
    if (record.camera) {
      const [fx, fy] = focalsOf(record.camera);
      row('camera', `${record.camera.model}, ${record.camera.width}×${record.camera.height}`);
      // A photo that was not localized may have no focal length (it is estimated with the pose).
      if (fx > 0) row('focal', fx === fy ? `${fixed(fx, 1)} px` : `${fixed(fx, 1)}, ${fixed(fy, 1)} px`);
    }
    const parts = [el('table', null, rows)];

    const times = record.times_ms || {};
    const stages = Object.keys(times).filter((key) => key !== 'total' && typeof times[key] === 'number');
    const timeRows = stages.map((key) =>
      el('tr', null, el('td', null, key.replace(/_/g, ' ')), el('td', { class: 'num' }, fixed(times[key], 1))));
    if (typeof times.total === 'number') {
      timeRows.push(el('tr', null, el('td', null, el('b', null, 'total')),
        el('td', { class: 'num' }, el('b', null, fixed(times.total, 1)))));
    }
    if (timeRows.length && compactTimes) {
      parts.push(el('details', null, el('summary', null, `times: ${fixed(times.total, 1)} ms in all`), el('table', null, timeRows)));
    } else if (timeRows.length) {
      parts.push(el('h3', null, 'times (ms)'), el('table', null, timeRows));
    }
    return parts;
  }

  // The pose buttons: look at the whole scene, or come close to the ellipsoid.
  function viewButtons(record) {
    const buttons = [el('button', { onclick: () => showAll() }, 'show all')];
    const drawn = results.find((r) => r.record === record && r.object);
    if (drawn) {
      const center = new THREE.Vector3(...record.pose.center);
      const radius = (record.covariance && record.covariance.position_radius95) || frame.extent * 0.01;
      buttons.push(' ', el('button', { onclick: () => focusOn(center, frame.extent * 0.5) }, 'go to pose'));
      buttons.push(' ', el('button', { onclick: () => focusOn(center, radius * 12) }, 'zoom to ellipsoid'));
    }
    return el('div', null, buttons);
  }

  function showSingle(record) {
    ui.result.replaceChildren(el('h2', null, record.name || 'photo'), ...recordDetails(record), viewButtons(record));
    ui.result.hidden = false;
  }

  // A session: the frames so far (click one for its details), then the chosen frame's details.
  function showSession(total, chosen) {
    const modeClass = (r) => (r.record.success ? 'ok' : 'bad');
    const frameRows = results.map((r, i) => el('tr', { onclick: () => showSession(total, r.record) },
      el('td', null, `${i + 1}. ${r.record.name}`),
      el('td', { class: modeClass(r) }, r.record.tracking ? r.record.tracking.mode : (r.record.success ? 'posed' : 'failed')),
      el('td', { class: 'num' }, typeof r.record.num_inliers === 'number' ? r.record.num_inliers : ''),
      el('td', { class: 'num' }, r.record.times_ms ? `${fixed(r.record.times_ms.total, 0)} ms` : '')));
    const record = chosen || (results.length ? results[results.length - 1].record : null);
    ui.result.replaceChildren(
      el('h2', null, `session: ${results.length} of ${total} frames`),
      el('table', { id: 'frames' }, frameRows),
      ...(record ? [el('h2', { class: 'frame' }, record.name), ...recordDetails(record, true), viewButtons(record)] : []));
    ui.result.hidden = false;
  }

  // ---------------------------------------------------------------- photos in

  async function localizeOne(file) {
    setStatus(`localizing ${file.name}…`);
    const record = await api(`/v1/localize?index=${encodeURIComponent(indexName)}`,
      { method: 'POST', body: photoForm(file), timeoutMs: PHOTO_TIMEOUT_MS });
    await drawRecord(record, file);
    showSingle(record);
    publish(record);
    setStatus(record.success
      ? `${file.name}: localized in ${fixed(record.times_ms && record.times_ms.total, 0)} ms`
      : `${file.name}: not localized`);
  }

  // Several photos: one session, frames in name order, each sent when the last is answered
  // (a session tracks one frame at a time). The session is ended even after an error.
  async function runSession(files) {
    document.body.dataset.session = 'running';
    const started = await api(`/v1/sessions?index=${encodeURIComponent(indexName)}`, { method: 'POST' });
    const id = started.session;
    try {
      showSession(files.length, null);
      for (let i = 0; i < files.length; i++) {
        setStatus(`session: frame ${i + 1} of ${files.length}, ${files[i].name}…`);
        let record;
        try {
          record = await api(`/v1/sessions/${id}/frames`,
            { method: 'POST', body: photoForm(files[i]), timeoutMs: PHOTO_TIMEOUT_MS });
        } catch (e) {
          // One frame's refusal (too large, not a photo) need not end the others.
          if (e.status === 401 || e.status === 404 || !e.status) throw e;
          record = { name: files[i].name, success: false, failure_reason: e.message };
        }
        await drawRecord(record, files[i]);
        showSession(files.length, null);
        publish(record);
      }
      setStatus(`session: ${results.filter((r) => r.object).length} of ${files.length} frames posed`);
    } finally {
      await api(`/v1/sessions/${id}`, { method: 'DELETE' }).catch(() => { /* it expires anyway */ });
      document.body.dataset.session = 'ended';
    }
  }

  async function takePhotos(fileList) {
    const files = [...fileList].filter((f) => f.size > 0);
    if (files.length === 0) return;
    if (busy) {
      setStatus('still busy with the last photos; drop again when they are done');
      return;
    }
    if (document.body.dataset.map !== 'loaded') {
      setStatus('the map is not loaded yet', true);
      return;
    }
    // Name order with numbers compared as numbers: frame_9 before frame_10.
    files.sort((a, b) => a.name.localeCompare(b.name, 'en', { numeric: true }));
    busy = true;
    setState('busy');
    clearResults();
    try {
      if (files.length === 1) await localizeOne(files[0]);
      else await runSession(files);
    } catch (e) {
      showApiError(e);
      setState('error');
    } finally {
      busy = false;
      ui.input.value = '';  // so that choosing the same photo again is a change
    }
  }

  ui.input.addEventListener('change', () => takePhotos(ui.input.files));

  // The whole window is a drop zone.
  let dragDepth = 0;
  window.addEventListener('dragenter', (e) => { e.preventDefault(); dragDepth++; document.body.classList.add('dragging'); });
  window.addEventListener('dragleave', () => { if (--dragDepth <= 0) { dragDepth = 0; document.body.classList.remove('dragging'); } });
  window.addEventListener('dragover', (e) => e.preventDefault());
  window.addEventListener('drop', (e) => {
    e.preventDefault();
    dragDepth = 0;
    document.body.classList.remove('dragging');
    if (e.dataTransfer && e.dataTransfer.files.length) takePhotos(e.dataTransfer.files);
  });

  loadInfo();
})();
