// A photo pair for the browser checks of the visual-odometry lesson, made here rather
// than stored: the scene of crates/slamlab-sim/src/vision/photos/synthetic.rs (a facade
// 9 m away covered in random grey cells of 8 cm and 24 cm, a box face 5 m away, the
// ground 1.2 m below the camera) seen by a 640 x 480 pinhole camera with a 60° field of
// view from two poses, written as 8-bit grey PNG files.

import { deflateSync } from "node:zlib";

const WIDTH = 640;
const HEIGHT = 480;
const FOCAL = WIDTH / 2 / Math.tan(Math.PI / 6);

// A deterministic grey level for a cell of a plane's texture (a 32-bit integer hash;
// not the same bits as the Rust scene, the same kind of texture).
function cellValue(plane, a, b) {
  let h = (Math.imul(plane, 0x9e3779b1) ^ Math.imul(a, 0x85ebca6b) ^ Math.imul(b, 0xc2b2ae35)) >>> 0;
  h = Math.imul(h ^ (h >>> 16), 0x7feb352d) >>> 0;
  h = Math.imul(h ^ (h >>> 15), 0x846ca68b) >>> 0;
  return (h ^ (h >>> 16)) & 0xff;
}

function texture(plane, a, b) {
  const fine = cellValue(plane, Math.floor(a / 0.08), Math.floor(b / 0.08));
  const coarse = cellValue(plane + 7, Math.floor(a / 0.24), Math.floor(b / 0.24));
  return 0.5 * fine + 0.5 * coarse;
}

// The grey level seen along a ray from `o` in direction `d` (left camera frame: x right,
// y down, z forward), 128 where it meets nothing.
function cast(o, d) {
  let best = Infinity;
  let grey = 128;
  const consider = (s, plane, coords) => {
    if (!(s > 1e-6 && s < best)) return;
    const p = [o[0] + d[0] * s, o[1] + d[1] * s, o[2] + d[2] * s];
    const c = coords(p);
    if (c) {
      best = s;
      grey = texture(plane, c[0], c[1]);
    }
  };
  consider((9 - o[2]) / d[2], 1, (p) => [p[0], p[1]]);
  consider((5 - o[2]) / d[2], 2, (p) => (p[0] > -1.6 && p[0] < 0.4 && p[1] > -0.6 && p[1] < 1.0 ? [p[0], p[1]] : null));
  consider((1.2 - o[1]) / d[1], 3, (p) => (p[2] > 0.5 ? [p[0], p[2]] : null));
  return grey;
}

// R = Ry(pitch) Rx(roll), as nalgebra's from_euler_angles(roll, pitch, 0).
function rotation(roll, pitch) {
  const [cr, sr, cp, sp] = [Math.cos(roll), Math.sin(roll), Math.cos(pitch), Math.sin(pitch)];
  return [
    [cp, sp * sr, sp * cr],
    [0, cr, -sr],
    [-sp, cp * sr, cp * cr],
  ];
}

// The image of the camera with X_cam = R X_left + t, 2 x 2 samples a pixel.
function render(r, t) {
  // Camera centre -Rᵀ t; a ray's direction Rᵀ K⁻¹ [u, v, 1].
  const origin = [0, 1, 2].map((j) => -(r[0][j] * t[0] + r[1][j] * t[1] + r[2][j] * t[2]));
  const grey = new Uint8Array(WIDTH * HEIGHT);
  for (let v = 0; v < HEIGHT; v++) {
    for (let u = 0; u < WIDTH; u++) {
      let sum = 0;
      for (const [du, dv] of [[0.25, 0.25], [0.75, 0.25], [0.25, 0.75], [0.75, 0.75]]) {
        const ray = [(u + du - WIDTH / 2) / FOCAL, (v + dv - HEIGHT / 2) / FOCAL, 1];
        const d = [0, 1, 2].map((j) => r[0][j] * ray[0] + r[1][j] * ray[1] + r[2][j] * ray[2]);
        sum += cast(origin, d);
      }
      grey[v * WIDTH + u] = Math.max(0, Math.min(255, Math.round(sum / 4)));
    }
  }
  return grey;
}

const CRC_TABLE = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});

function crc32(bytes) {
  let c = 0xffffffff;
  for (const b of bytes) c = CRC_TABLE[(c ^ b) & 0xff] ^ (c >>> 8);
  return (c ^ 0xffffffff) >>> 0;
}

function chunk(type, body) {
  const head = Buffer.alloc(8);
  head.writeUInt32BE(body.length, 0);
  head.write(type, 4, "latin1");
  const crc = Buffer.alloc(4);
  crc.writeUInt32BE(crc32(Buffer.concat([head.subarray(4), body])), 0);
  return Buffer.concat([head, body, crc]);
}

/** An 8-bit grey image as PNG bytes. */
export function encodeGreyPng(grey, width, height) {
  const header = Buffer.alloc(13);
  header.writeUInt32BE(width, 0);
  header.writeUInt32BE(height, 4);
  header[8] = 8; // bit depth
  header[9] = 0; // grey
  const raw = Buffer.alloc((width + 1) * height);
  for (let y = 0; y < height; y++) {
    raw[y * (width + 1)] = 0; // no filter
    raw.set(grey.subarray(y * width, (y + 1) * width), y * (width + 1) + 1);
  }
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk("IHDR", header),
    chunk("IDAT", deflateSync(raw)),
    chunk("IEND", Buffer.alloc(0)),
  ]);
}

/**
 * The two photos as PNG bytes and the true rotation angle between them (degrees): the
 * second camera turned 4° about the vertical (and 0.57° about x) and moved 0.5 m sideways.
 */
export function photoPair() {
  const identity = [
    [1, 0, 0],
    [0, 1, 0],
    [0, 0, 1],
  ];
  const r = rotation(0.01, (4 * Math.PI) / 180);
  const trace = r[0][0] + r[1][1] + r[2][2];
  return {
    left: encodeGreyPng(render(identity, [0, 0, 0]), WIDTH, HEIGHT),
    right: encodeGreyPng(render(r, [-0.5, 0.02, -0.15]), WIDTH, HEIGHT),
    rotationDeg: (Math.acos(Math.min(1, (trace - 1) / 2)) * 180) / Math.PI,
  };
}
