// A real converter reads spotshell's 3DGS export: @playcanvas/splat-transform turns the PLY into
// CSV (every value, as it read them) and into its own PLY, which spotshell reads back.
// usage: node splat_transform_test.mjs --spotshell BIN --scene FILE --work DIR
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { fail, parseArgs, readPly, spotshell } from './common.mjs';

const args = parseArgs(['spotshell', 'scene', 'work']);
fs.mkdirSync(args.work, { recursive: true });
const here = path.dirname(fileURLToPath(import.meta.url));
const cli = path.join(args.modules || path.join(here, 'node_modules'),
                      '@playcanvas/splat-transform/bin/cli.mjs');
const ply = path.join(args.work, 'splats.ply');
spotshell(args.spotshell, ['export', '--format', '3dgs', '--scene', args.scene, '--out', ply]);
const ours = readPly(ply);

const csv = path.join(args.work, 'splats.csv');
const back = path.join(args.work, 'splat_transform.ply');
const convert = (out) => {
    try {
        execFileSync(process.execPath, [cli, '-q', '-w', ply, out], { stdio: ['ignore', 'pipe', 'pipe'] });
    } catch (e) {
        fail(`splat-transform ${ply} ${out}: ${e.stderr || e.message}`);
    }
};
convert(csv);
convert(back);

// The CSV: a header of property names, then one row per splat.
const lines = fs.readFileSync(csv, 'utf8').trim().split('\n');
const names = lines[0].split(',');
if (lines.length - 1 !== ours.count)
    fail(`splat-transform read ${lines.length - 1} splats, spotshell wrote ${ours.count}`);
for (const name of ['x', 'y', 'z', 'f_dc_0', 'f_dc_1', 'f_dc_2', 'opacity', 'scale_0', 'scale_1',
                    'scale_2', 'rot_0', 'rot_1', 'rot_2', 'rot_3'])
    if (!names.includes(name))
        fail(`splat-transform's CSV has no ${name} (${names.join(' ')})`);
let compared = 0;
for (let i = 0; i < ours.count; ++i) {
    const row = lines[i + 1].split(',').map(Number);
    for (let j = 0; j < names.length; ++j) {
        const k = ours.names.indexOf(names[j]);
        if (k < 0)
            fail(`splat-transform added a property ${names[j]}`);
        const want = ours.values[i * ours.names.length + k];
        if (Math.fround(row[j]) !== want)
            fail(`splat ${i}'s ${names[j]}: splat-transform read ${row[j]}, spotshell wrote ${want}`);
        ++compared;
    }
}
// Its PLY goes back through spotshell's reader.
const info = spotshell(args.spotshell, ['info', '--splats', back]);
const count = Number(/count\s+(\d+)/.exec(info)[1]);
if (count !== ours.count)
    fail(`spotshell info read ${count} splats from splat-transform's PLY, ${ours.count} were written`);
console.log(`splat-transform read ${ours.count} splats, ${compared} values equal to the float; ` +
            `its PLY reads back in spotshell (${count} splats)`);
