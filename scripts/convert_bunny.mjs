// Convert the npm package `bunny` (v1.0.1, public domain, Mikola Lysenko; data from the Stanford
// 3D scanning repository) into presets/meshes/bunny.ply: binary little-endian PLY, positions only.
//
//   cd /tmp/npmb && npm pack bunny && tar xzf bunny-1.0.1.tgz
//   node scripts/convert_bunny.mjs /tmp/npmb/package/index.js [out.ply]
//
// Positions are scaled by 0.1 so the bunny is about 0.97 world units tall with its feet at y ~ 0.
// The winding is checked with the signed volume (positive means counter-clockwise seen from
// outside, what spotshell expects) and every triangle is flipped if it comes out negative.
// No dependencies: node's own modules only.
import {writeFileSync} from 'node:fs';
import {createRequire} from 'node:module';
import {dirname, resolve} from 'node:path';
import {fileURLToPath} from 'node:url';

const kScale = 0.1;

const source = process.argv[2];
if (!source) {
    console.error('usage: node scripts/convert_bunny.mjs PATH/TO/bunny/index.js [out.ply]');
    process.exit(2);
}
const repoRoot = resolve(dirname(fileURLToPath(import.meta.url)), '..');
const outPath = process.argv[3] ?? resolve(repoRoot, 'presets/meshes/bunny.ply');

const require = createRequire(import.meta.url);
const bunny = require(resolve(source));
const positions = bunny.positions.map((p) => p.map((c) => c * kScale));
let cells = bunny.cells.map((c) => [...c]);

for (const p of positions) {
    if (p.length !== 3 || !p.every(Number.isFinite))
        throw new Error(`bad position ${p}`);
}
for (const c of cells) {
    if (c.length !== 3 || !c.every((i) => Number.isInteger(i) && i >= 0 && i < positions.length))
        throw new Error(`bad cell ${c}`);
}

// Signed volume by the divergence theorem: sum over triangles of p0 . (p1 x p2) / 6.
function signedVolume() {
    let volume = 0;
    for (const [a, b, c] of cells) {
        const [p, q, r] = [ positions[a], positions[b], positions[c] ];
        volume += p[0] * (q[1] * r[2] - q[2] * r[1]) - p[1] * (q[0] * r[2] - q[2] * r[0]) +
                  p[2] * (q[0] * r[1] - q[1] * r[0]);
    }
    return volume / 6;
}

let volume = signedVolume();
let flipped = false;
if (volume < 0) {
    cells = cells.map(([ a, b, c ]) => [a, c, b]);
    flipped = true;
    volume = signedVolume();
}

const header =
    'ply\n' +
    'format binary_little_endian 1.0\n' +
    'comment Stanford bunny via npm package bunny 1.0.1 (public domain), scaled by 0.1\n' +
    `element vertex ${positions.length}\n` +
    'property float x\nproperty float y\nproperty float z\n' +
    `element face ${cells.length}\n` +
    'property list uchar int vertex_indices\n' +
    'end_header\n';
const headerBytes = Buffer.from(header, 'ascii');
const body = Buffer.alloc(positions.length * 12 + cells.length * 13);
let at = 0;
for (const p of positions) {
    for (const c of p)
        at = body.writeFloatLE(c, at);
}
for (const c of cells) {
    at = body.writeUInt8(3, at);
    for (const i of c)
        at = body.writeInt32LE(i, at);
}
writeFileSync(outPath, Buffer.concat([ headerBytes, body ]));

const ys = positions.map((p) => p[1]);
console.log(
    `wrote ${outPath}: ${positions.length} vertices, ${cells.length} triangles, ` +
    `y in [${Math.min(...ys).toFixed(4)}, ${Math.max(...ys).toFixed(4)}], ` +
    `signed volume ${volume.toFixed(6)}${flipped ? ' (winding flipped)' : ' (winding kept)'}`);
