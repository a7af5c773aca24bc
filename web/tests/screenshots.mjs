// The pictures of SLAM Lab's README and lesson documents, made from the built site in
// headless Chromium: each lesson opened at a fixed URL (its seed, and `tick=` so that
// the picture shows the lesson mid-run), photographed, scaled down and written as a
// small palette PNG into docs/images/.
//
//   scripts/screenshots.sh     all of them (it runs web/test.sh in this mode)
//
// web/test.sh makes one of them in every run (the check "screenshots: …"), so the
// script cannot stop working unnoticed. With SLAMLAB_SCREENSHOTS=DIR that check makes
// every picture into DIR instead.

import { deflateSync } from "node:zlib";
import { decodePng, imageStats } from "./png.mjs";

/** The README's large picture: one lesson in the whole app, panels open. */
export const HERO = {
  name: "slamlab",
  query: "lesson=landmark-slam&seed=7&estimator=ekf,ukf&tick=150",
  viewport: { width: 1280, height: 800 },
  width: 960,
};

/**
 * One picture per lesson, the lesson as a lecture figure shows it (embed=1: the map, its
 * plots and the time bar), 800 x 600 for the lesson's document; and for the README's
 * table a thumbnail, 240 x 180, of the part of it that tells the lesson at a glance
 * (`crop`: x, y, width, height in the page's pixels, 4:3).
 */
export const LESSON_SHOTS = [
  { id: "landmark-slam", query: "seed=7&estimator=ekf,ukf&tick=150", crop: [210, 140, 380, 285] },
  { id: "kidnap", query: "map=maze&particles=2000&seed=3&tick=120", crop: [205, 148, 360, 270] },
  { id: "pose-graph", query: "example=manhattan&seed=1&tick=1", crop: [200, 108, 400, 300] },
  { id: "resampling", query: "weights=two-modes&particles=20&seed=3&tick=3", crop: [0, 90, 400, 300] },
  { id: "fusion", query: "seed=3&modes=differential,relative&tick=120", crop: [220, 150, 320, 240] },
  { id: "mapping", query: "map=maze&poses=scan-to-map&seed=1&tick=600", crop: [220, 135, 360, 270] },
  { id: "cartographer", query: "map=maze&kidnap-at=152&seed=3&tick=200", crop: [305, 215, 240, 180] },
  { id: "filters", query: "seed=1", crop: [400, 90, 400, 300] },
  { id: "visual-odometry", query: "seed=3&tick=5", crop: [190, 88, 420, 315] },
].map(({ id, query, crop }) => ({
  id,
  name: `lesson-${id}`,
  query: `lesson=${id}&${query}&embed=1`,
  viewport: { width: 800, height: 600 },
  width: 800,
  thumb: { crop, width: 240 },
}));

/** The page's state as the app reports it (slamlab_test_state). */
async function appState(page) {
  return JSON.parse(await page.evaluate(() => window.slamlab.slamlab_test_state()));
}

/**
 * Photographs a page that shows `shot.query` and is running (#status "running"): waits
 * until the lesson has drawn a few frames at its tick and the picture holds still, then
 * returns the picture at `shot.width` pixels wide and, if the shot has one, at
 * `shot.thumb`, each as palette PNG bytes with its decoded size.
 */
export async function takePictures(page, shot) {
  const deadline = Date.now() + 60_000;
  let state = await appState(page);
  // The app runs the URL's tick= before its first frame; a paused lesson then draws a
  // few frames and waits for input: by the third, fonts, plots and the layout have settled.
  while (state.frames < 3) {
    if (Date.now() > deadline) throw new Error(`${shot.name}: fewer than 3 frames drawn: ${JSON.stringify(state)}`);
    await new Promise((resolve) => setTimeout(resolve, 100));
    state = await appState(page);
  }
  // A PNG with only the canvas: the mouse away from it, so no hover highlights.
  await page.mouse.move(shot.viewport.width - 1, shot.viewport.height - 1);
  await new Promise((resolve) => setTimeout(resolve, 500));
  const image = decodePng(await page.screenshot({ type: "png" }));
  const stats = imageStats(image);
  if (stats.distinctColours < 16 || stats.nonDominantShare < 0.05) {
    throw new Error(`${shot.name}: the page looks blank (${stats.distinctColours} colours)`);
  }
  const pictures = { large: encodePalettePng(quantize(resize(image, shot.width))) };
  if (shot.thumb) {
    const part = crop(image, shot.thumb.crop);
    pictures.small = encodePalettePng(quantize(resize(part, shot.thumb.width)));
  }
  return { pictures, state };
}

/** The size in pixels of a shot's picture (`large`) or thumbnail (`small`). */
export function pictureSize(shot, size) {
  const [, , w, h] = size === "small" ? shot.thumb.crop : [0, 0, shot.viewport.width, shot.viewport.height];
  const width = size === "small" ? shot.thumb.width : shot.width;
  return { width, height: Math.round((h * width) / w) };
}

// ---------------------------------------------------------------------------------------
// Scaling, a 256-colour palette and PNG encoding, so that the pictures stay small
// (a thumbnail of a few tens of kB) without an image library.

/** The part `[x, y, width, height]` of an RGB(A) image, as RGB. */
export function crop(image, [x, y, width, height]) {
  const { channels, data } = image;
  if (x < 0 || y < 0 || x + width > image.width || y + height > image.height) {
    throw new Error(`the crop ${[x, y, width, height]} is not inside the ${image.width} x ${image.height} picture`);
  }
  const out = Buffer.alloc(width * height * 3);
  for (let row = 0; row < height; row++) {
    for (let col = 0; col < width; col++) {
      const o = ((y + row) * image.width + x + col) * channels;
      out.set(data.subarray(o, o + 3), (row * width + col) * 3);
    }
  }
  return { width, height, channels: 3, data: out };
}

/** Scales an RGB(A) image to `width` pixels wide (height in proportion) by area averaging. */
export function resize(image, width) {
  const { width: w0, height: h0, channels, data } = image;
  if (width >= w0) return { width: w0, height: h0, channels: 3, data: rgbOf(image) };
  const height = Math.round((h0 * width) / w0);
  // The weights of the source columns (rows) each target column (row) covers.
  const spans = (from, to) => {
    const scale = from / to;
    return Array.from({ length: to }, (_, i) => {
      const a = i * scale;
      const b = (i + 1) * scale;
      const taps = [];
      for (let s = Math.floor(a); s < Math.min(from, Math.ceil(b)); s++) {
        taps.push([s, Math.min(b, s + 1) - Math.max(a, s)]);
      }
      return taps;
    });
  };
  const xs = spans(w0, width);
  const ys = spans(h0, height);
  const rows = new Float64Array(width * h0 * 3);
  for (let y = 0; y < h0; y++) {
    for (let x = 0; x < width; x++) {
      let r = 0, g = 0, b = 0, sum = 0;
      for (const [s, wgt] of xs[x]) {
        const o = (y * w0 + s) * channels;
        r += wgt * data[o];
        g += wgt * data[o + 1];
        b += wgt * data[o + 2];
        sum += wgt;
      }
      const o = (y * width + x) * 3;
      rows[o] = r / sum;
      rows[o + 1] = g / sum;
      rows[o + 2] = b / sum;
    }
  }
  const out = Buffer.alloc(width * height * 3);
  for (let y = 0; y < height; y++) {
    for (let x = 0; x < width; x++) {
      let r = 0, g = 0, b = 0, sum = 0;
      for (const [s, wgt] of ys[y]) {
        const o = (s * width + x) * 3;
        r += wgt * rows[o];
        g += wgt * rows[o + 1];
        b += wgt * rows[o + 2];
        sum += wgt;
      }
      const o = (y * width + x) * 3;
      out[o] = Math.round(r / sum);
      out[o + 1] = Math.round(g / sum);
      out[o + 2] = Math.round(b / sum);
    }
  }
  return { width, height, channels: 3, data: out };
}

function rgbOf({ width, height, channels, data }) {
  if (channels === 3) return Buffer.from(data);
  const out = Buffer.alloc(width * height * 3);
  for (let i = 0; i < width * height; i++) data.copy(out, i * 3, i * channels, i * channels + 3);
  return out;
}

/**
 * The image with at most 256 colours: every colour when it has no more, else a palette
 * by median cut over its colours (weighted by how many pixels have each), each pixel
 * mapped to the nearest entry. No dithering: flat interface colours stay flat and
 * compress well.
 */
export function quantize(image) {
  const { width, height, data } = image;
  const pixels = width * height;
  const counts = new Map();
  for (let i = 0; i < pixels; i++) {
    const rgb = (data[3 * i] << 16) | (data[3 * i + 1] << 8) | data[3 * i + 2];
    counts.set(rgb, (counts.get(rgb) ?? 0) + 1);
  }
  let palette;
  if (counts.size <= 256) {
    palette = [...counts.keys()];
  } else {
    const colours = [...counts.entries()].map(([rgb, n]) => [(rgb >> 16) & 255, (rgb >> 8) & 255, rgb & 255, n]);
    const boxes = [colours];
    const range = (box, k) => {
      let lo = 255, hi = 0;
      for (const c of box) {
        if (c[k] < lo) lo = c[k];
        if (c[k] > hi) hi = c[k];
      }
      return hi - lo;
    };
    while (boxes.length < 256) {
      // Split the box with the widest channel (ties: more pixels), at its pixel median.
      let best = -1, bestScore = 0, bestChannel = 0;
      boxes.forEach((box, i) => {
        if (box.length < 2) return;
        const widths = [0, 1, 2].map((k) => range(box, k));
        const k = widths.indexOf(Math.max(...widths));
        const mass = box.reduce((s, c) => s + c[3], 0);
        const score = widths[k] * Math.sqrt(mass);
        if (score > bestScore) [best, bestScore, bestChannel] = [i, score, k];
      });
      if (best < 0) break;
      const box = boxes[best].sort((a, b) => a[bestChannel] - b[bestChannel]);
      const half = box.reduce((s, c) => s + c[3], 0) / 2;
      let acc = 0, cut = 1;
      for (; cut < box.length - 1; cut++) {
        acc += box[cut - 1][3];
        if (acc >= half) break;
      }
      boxes.splice(best, 1, box.slice(0, cut), box.slice(cut));
    }
    palette = boxes.map((box) => {
      let r = 0, g = 0, b = 0, n = 0;
      for (const c of box) {
        r += c[0] * c[3];
        g += c[1] * c[3];
        b += c[2] * c[3];
        n += c[3];
      }
      return (Math.round(r / n) << 16) | (Math.round(g / n) << 8) | Math.round(b / n);
    });
  }
  const rgbs = palette.map((p) => [(p >> 16) & 255, (p >> 8) & 255, p & 255]);
  const nearest = new Map();
  const indices = Buffer.alloc(pixels);
  for (let i = 0; i < pixels; i++) {
    const rgb = (data[3 * i] << 16) | (data[3 * i + 1] << 8) | data[3 * i + 2];
    let index = nearest.get(rgb);
    if (index === undefined) {
      const [r, g, b] = [(rgb >> 16) & 255, (rgb >> 8) & 255, rgb & 255];
      let bestDistance = Infinity;
      rgbs.forEach(([pr, pg, pb], k) => {
        const d = 2 * (r - pr) ** 2 + 4 * (g - pg) ** 2 + 3 * (b - pb) ** 2;
        if (d < bestDistance) [index, bestDistance] = [k, d];
      });
      nearest.set(rgb, index);
    }
    indices[i] = index;
  }
  return { width, height, palette: rgbs, indices };
}

const CRC_TABLE = Array.from({ length: 256 }, (_, n) => {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c >>> 0;
});

function chunk(type, body) {
  const typed = Buffer.concat([Buffer.from(type, "latin1"), body]);
  let c = 0xffffffff;
  for (const byte of typed) c = CRC_TABLE[(c ^ byte) & 0xff] ^ (c >>> 8);
  const out = Buffer.alloc(12 + body.length);
  out.writeUInt32BE(body.length, 0);
  typed.copy(out, 4);
  out.writeUInt32BE((c ^ 0xffffffff) >>> 0, 8 + body.length);
  return out;
}

/** A palette image ({ width, height, palette: [[r, g, b]…], indices }) as PNG bytes. */
export function encodePalettePng({ width, height, palette, indices }) {
  const header = Buffer.alloc(13);
  header.writeUInt32BE(width, 0);
  header.writeUInt32BE(height, 4);
  header[8] = 8; // bits per index
  header[9] = 3; // palette
  const raw = Buffer.alloc((width + 1) * height);
  for (let y = 0; y < height; y++) indices.copy(raw, y * (width + 1) + 1, y * width, (y + 1) * width);
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk("IHDR", header),
    chunk("PLTE", Buffer.from(palette.flat())),
    chunk("IDAT", deflateSync(raw, { level: 9 })),
    chunk("IEND", Buffer.alloc(0)),
  ]);
}
