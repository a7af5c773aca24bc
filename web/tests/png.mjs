// A tiny PNG decoder and image statistics for the browser tests, so that the tests can
// look at their own screenshots without an image library. It reads what Chromium's
// screenshots are, 8-bit RGB or RGBA, and the 8-bit palette images of
// web/tests/screenshots.mjs; not interlaced.

import { inflateSync } from "node:zlib";

const PNG_SIGNATURE = Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]);

/** Decodes a PNG into { width, height, channels, data } (data: one byte per channel). */
export function decodePng(buffer) {
  if (!buffer.subarray(0, 8).equals(PNG_SIGNATURE)) throw new Error("not a PNG file");
  let offset = 8;
  let header = null;
  let palette = null;
  const idat = [];
  while (offset < buffer.length) {
    const length = buffer.readUInt32BE(offset);
    const type = buffer.toString("latin1", offset + 4, offset + 8);
    const body = buffer.subarray(offset + 8, offset + 8 + length);
    offset += 12 + length; // length, type, body, CRC
    if (type === "IHDR") {
      header = {
        width: body.readUInt32BE(0),
        height: body.readUInt32BE(4),
        bitDepth: body[8],
        colorType: body[9],
        interlace: body[12],
      };
    } else if (type === "PLTE") {
      palette = body;
    } else if (type === "IDAT") {
      idat.push(body);
    } else if (type === "IEND") {
      break;
    }
  }
  if (!header) throw new Error("PNG without IHDR");
  const { width, height, bitDepth, colorType, interlace } = header;
  const channels = { 2: 3, 3: 1, 6: 4 }[colorType];
  if (bitDepth !== 8 || !channels || interlace !== 0 || (colorType === 3 && !palette)) {
    throw new Error(`unsupported PNG: bit depth ${bitDepth}, colour type ${colorType}, interlace ${interlace}`);
  }
  const raw = inflateSync(Buffer.concat(idat));
  const stride = width * channels;
  const data = Buffer.alloc(stride * height);
  // Undo the per-row filters (PNG spec, section 9).
  for (let y = 0; y < height; y++) {
    const filter = raw[y * (stride + 1)];
    const src = y * (stride + 1) + 1;
    const dst = y * stride;
    for (let x = 0; x < stride; x++) {
      const a = x >= channels ? data[dst + x - channels] : 0; // left
      const b = y > 0 ? data[dst + x - stride] : 0; // up
      const c = x >= channels && y > 0 ? data[dst + x - stride - channels] : 0; // up-left
      let predictor;
      switch (filter) {
        case 0: predictor = 0; break;
        case 1: predictor = a; break;
        case 2: predictor = b; break;
        case 3: predictor = (a + b) >> 1; break;
        case 4: {
          const p = a + b - c;
          const pa = Math.abs(p - a);
          const pb = Math.abs(p - b);
          const pc = Math.abs(p - c);
          predictor = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
          break;
        }
        default: throw new Error(`bad PNG filter ${filter} in row ${y}`);
      }
      data[dst + x] = (raw[src + x] + predictor) & 0xff;
    }
  }
  if (colorType === 3) {
    // Palette indices to RGB.
    const rgb = Buffer.alloc(width * height * 3);
    for (let i = 0; i < width * height; i++) palette.copy(rgb, 3 * i, 3 * data[i], 3 * data[i] + 3);
    return { width, height, channels: 3, data: rgb };
  }
  return { width, height, channels, data };
}

/**
 * How much is on the image: the number of distinct RGB colours, the most common colour
 * and the share of pixels that are *not* that colour. A blank canvas has one colour
 * (or a handful, from a gradient) and almost every pixel equal to it.
 */
export function imageStats(image) {
  const { width, height, channels, data } = image;
  const counts = new Map();
  for (let i = 0; i < width * height; i++) {
    const o = i * channels;
    const rgb = (data[o] << 16) | (data[o + 1] << 8) | data[o + 2];
    counts.set(rgb, (counts.get(rgb) ?? 0) + 1);
  }
  let dominant = 0;
  let dominantCount = 0;
  for (const [rgb, count] of counts) {
    if (count > dominantCount) {
      dominant = rgb;
      dominantCount = count;
    }
  }
  const pixels = width * height;
  return {
    width,
    height,
    distinctColours: counts.size,
    dominantColour: `#${dominant.toString(16).padStart(6, "0")}`,
    nonDominantShare: (pixels - dominantCount) / pixels,
  };
}

/**
 * The share of pixels that differ between two images of the same size by more than
 * `tolerance` in any of R, G, B.
 */
export function changedShare(a, b, tolerance = 16) {
  if (a.width !== b.width || a.height !== b.height) return 1;
  let changed = 0;
  const pixels = a.width * a.height;
  for (let i = 0; i < pixels; i++) {
    const oa = i * a.channels;
    const ob = i * b.channels;
    for (let k = 0; k < 3; k++) {
      if (Math.abs(a.data[oa + k] - b.data[ob + k]) > tolerance) {
        changed++;
        break;
      }
    }
  }
  return changed / pixels;
}
