// Helpers shared by the interop tests: arguments, running spotshell, reading a 3DGS PLY.
import { execFileSync } from 'node:child_process';
import fs from 'node:fs';

/// --name value pairs into an object; every name in `required` must be there.
export function parseArgs(required) {
    const args = {};
    const argv = process.argv.slice(2);
    for (let i = 0; i + 1 < argv.length; i += 2)
        args[argv[i].replace(/^--/, '')] = argv[i + 1];
    for (const name of required)
        if (args[name] === undefined)
            fail(`missing --${name}`);
    return args;
}

export function fail(message) {
    console.error(`FAIL: ${message}`);
    process.exit(1);
}

/// Run spotshell; its standard output (the command's failure fails the test with its stderr).
export function spotshell(bin, args) {
    try {
        return execFileSync(bin, args, { encoding: 'utf8', stdio: ['ignore', 'pipe', 'pipe'] });
    } catch (e) {
        fail(`spotshell ${args.join(' ')}: ${e.stderr || e.message}`);
    }
}

/// A binary little-endian PLY of float vertex properties: { names, count, values: Float32Array }.
export function readPly(file) {
    const bytes = fs.readFileSync(file);
    const end = bytes.indexOf('end_header\n');
    if (end < 0)
        fail(`${file}: no end_header`);
    const header = bytes.subarray(0, end).toString('latin1').split('\n');
    const count = Number(header.find((l) => l.startsWith('element vertex')).split(' ')[2]);
    const names = header.filter((l) => l.startsWith('property float')).map((l) => l.split(' ')[2]);
    const body = bytes.subarray(end + 'end_header\n'.length);
    if (body.length !== count * names.length * 4)
        fail(`${file}: ${body.length} body bytes for ${count} x ${names.length} floats`);
    const values = new Float32Array(count * names.length);
    const view = new DataView(body.buffer, body.byteOffset, body.byteLength);
    for (let i = 0; i < values.length; ++i)
        values[i] = view.getFloat32(4 * i, true);
    return { names, count, values };
}

/// `spotshell compare A B --json`'s PSNR (dB).
export function psnr(bin, reference, test) {
    return JSON.parse(spotshell(bin, ['compare', reference, test, '--json'])).psnr;
}
