// cwloc-serve's viewer: the geometry that needs no page (serve/viewer/viewer.js draws with it).
// COLMAP's conventions: camera frame x right, y down, z forward; poses cam_from_world; camera
// parameters in COLMAP's order.
'use strict';

const CwlocGeometry = (function () {
  // The value at `fraction` (0.5: the median) of a sorted copy: SfM points have outliers, which
  // medians and percentiles shrug off where means and extremes would not.
  function percentile(values, fraction) {
    if (values.length === 0) return 0;
    const sorted = Float64Array.from(values).sort();
    return sorted[Math.min(sorted.length - 1, Math.floor(fraction * sorted.length))];
  }

  // COLMAP's cam_from_world [w, x, y, z] -> three.js world_from_cam (the inverse: conjugate).
  function worldFromCam(qvec) {
    const [w, x, y, z] = qvec;
    return new THREE.Quaternion(-x, -y, -z, w).normalize();
  }

  // Centre: per-axis median; extent: the 85th percentile of the distances to it; up: minus the
  // cameras' mean y axis; view: from the cameras towards the points, seen level.
  function sceneFrame(xyz, cameras) {
    const n = xyz.length / 3;
    const center = new THREE.Vector3();
    if (n > 0) {
      const axis = (k) => { const a = new Float64Array(n); for (let i = 0; i < n; i++) a[i] = xyz[3 * i + k]; return a; };
      center.set(percentile(axis(0), 0.5), percentile(axis(1), 0.5), percentile(axis(2), 0.5));
    } else if (cameras.length > 0) {
      for (const c of cameras) center.add(c.center);
      center.divideScalar(cameras.length);
    }
    const distances = new Float64Array(n);
    for (let i = 0; i < n; i++) {
      distances[i] = Math.hypot(xyz[3 * i] - center.x, xyz[3 * i + 1] - center.y, xyz[3 * i + 2] - center.z);
    }
    let extent = percentile(distances, 0.85);
    if (!(extent > 0)) {
      extent = cameras.reduce((m, c) => Math.max(m, c.center.distanceTo(center)), 0) || 1;
    }

    const up = new THREE.Vector3();
    const forward = new THREE.Vector3();
    const cameraMean = new THREE.Vector3();
    for (const c of cameras) {
      up.sub(new THREE.Vector3(0, 1, 0).applyQuaternion(c.rotation));
      forward.add(new THREE.Vector3(0, 0, 1).applyQuaternion(c.rotation));
      cameraMean.add(c.center);
    }
    if (up.lengthSq() < 1e-12) up.set(0, -1, 0);  // no cameras: COLMAP models often have y down
    up.normalize();

    // Looking the way the photographers looked makes the first view familiar.
    const level = (v) => v.clone().addScaledVector(up, -v.dot(up));
    let viewDir = new THREE.Vector3();
    if (cameras.length > 0) {
      cameraMean.divideScalar(cameras.length);
      viewDir = level(center.clone().sub(cameraMean));
      if (viewDir.length() < 0.1 * extent) viewDir = level(forward);  // cameras all around
    }
    if (viewDir.lengthSq() < 1e-12) {
      viewDir = level(new THREE.Vector3(1, 0, 0));
      if (viewDir.lengthSq() < 1e-12) viewDir = level(new THREE.Vector3(0, 0, 1));
    }
    viewDir.normalize();

    // The box to show first, in (right, up, forward) coordinates: most points (percentiles
    // drop the outliers) and every camera.
    const axes = [new THREE.Vector3().crossVectors(viewDir, up), up.clone(), viewDir.clone()];
    const box = axes.map((axis) => {
      const along = new Float64Array(n);
      for (let i = 0; i < n; i++) along[i] = xyz[3 * i] * axis.x + xyz[3 * i + 1] * axis.y + xyz[3 * i + 2] * axis.z;
      let low = n ? percentile(along, 0.03) : Infinity;
      let high = n ? percentile(along, 0.97) : -Infinity;
      for (const c of cameras) { low = Math.min(low, c.center.dot(axis)); high = Math.max(high, c.center.dot(axis)); }
      if (!(low <= high)) { low = center.dot(axis) - extent; high = center.dot(axis) + extent; }
      return [low, high];
    });
    const home = new THREE.Vector3();
    axes.forEach((axis, k) => home.addScaledVector(axis, (box[k][0] + box[k][1]) / 2));
    const halfSizes = box.map(([low, high]) => Math.max((high - low) / 2, extent * 0.05));
    return { center, extent, up, viewDir, home, halfSizes };
  }

  // A frustum's lines in the camera frame (x right, y down, z forward), depth 1, for an image of
  // half-sizes hw, hh at depth 1; with a tick above the top edge to tell up from down.
  function frustumLines(hw, hh, withUpTick) {
    const a = [0, 0, 0];
    const c = [[-hw, -hh, 1], [hw, -hh, 1], [hw, hh, 1], [-hw, hh, 1]];  // top left, clockwise
    const segments = [];
    for (let i = 0; i < 4; i++) segments.push(a, c[i], c[i], c[(i + 1) % 4]);
    if (withUpTick) {
      const tip = [0, -hh * 1.45, 1];
      segments.push([-hw * 0.35, -hh, 1], tip, tip, [hw * 0.35, -hh, 1]);
    }
    return segments;
  }

  // The focal lengths in pixels from COLMAP's camera parameters: models with one focal length
  // (SIMPLE_*, RADIAL, ...) list it first; the others list fx, fy first.
  function focalsOf(cameraRecord) {
    const p = cameraRecord.params || [];
    const twoFocals = /^(PINHOLE|OPENCV|OPENCV_FISHEYE|FULL_OPENCV|FOV|THIN_PRISM_FISHEYE)$/.test(cameraRecord.model);
    return twoFocals ? [p[0], p[1]] : [p[0], p[0]];
  }

  // The eigenvalues and eigenvectors (columns of `vectors`) of a symmetric 3x3 matrix, by
  // Jacobi rotations: short, and exact enough for a drawing.
  function symmetricEigen3(matrix) {
    const a = matrix.map((row) => row.slice());
    const v = [[1, 0, 0], [0, 1, 0], [0, 0, 1]];
    const scale = Math.abs(a[0][0]) + Math.abs(a[1][1]) + Math.abs(a[2][2]) || 1;
    for (let sweep = 0; sweep < 50; sweep++) {
      const off = Math.abs(a[0][1]) + Math.abs(a[0][2]) + Math.abs(a[1][2]);
      if (off <= 1e-15 * scale) break;
      for (const [p, q] of [[0, 1], [0, 2], [1, 2]]) {
        if (a[p][q] === 0) continue;
        const theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        const t = (theta >= 0 ? 1 : -1) / (Math.abs(theta) + Math.sqrt(theta * theta + 1));
        const c = 1 / Math.sqrt(t * t + 1);
        const s = t * c;
        for (let k = 0; k < 3; k++) {  // a = a J
          const akp = a[k][p], akq = a[k][q];
          a[k][p] = c * akp - s * akq; a[k][q] = s * akp + c * akq;
        }
        for (let k = 0; k < 3; k++) {  // a = J^T a
          const apk = a[p][k], aqk = a[q][k];
          a[p][k] = c * apk - s * aqk; a[q][k] = s * apk + c * aqk;
        }
        for (let k = 0; k < 3; k++) {  // v = v J
          const vkp = v[k][p], vkq = v[k][q];
          v[k][p] = c * vkp - s * vkq; v[k][q] = s * vkp + c * vkq;
        }
      }
    }
    return { values: [a[0][0], a[1][1], a[2][2]], vectors: v };
  }

  return { percentile, worldFromCam, sceneFrame, frustumLines, focalsOf, symmetricEigen3 };
})();
