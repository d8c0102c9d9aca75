// A standard web 3DGS viewer shows spotshell's 3DGS export: @mkkellogg/gaussian-splats-3d in
// headless Chromium (software WebGL: SwiftShader) at the scene camera from cameras.json; its
// picture is compared with spotshell's reference image of the same view.
// usage: node viewer_test.mjs --spotshell BIN --scene FILE --size WxH --work DIR --floor DB
//        [--chromium BIN] [--modules DIR] [--mapping NAME]
import { spawn } from 'node:child_process';
import fs from 'node:fs';
import http from 'node:http';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { fail, parseArgs, psnr, spotshell } from './common.mjs';

const args = parseArgs(['spotshell', 'scene', 'size', 'work', 'floor']);
const here = path.dirname(fileURLToPath(import.meta.url));
const modules = args.modules || path.join(here, 'node_modules');
const work = path.resolve(args.work);
fs.mkdirSync(work, { recursive: true });
const ply = path.join(work, 'splats.ply');
// Unlit, both: the splats carry the lobes' own colours (a 3DGS viewer lights nothing).
const exported = spotshell(args.spotshell, ['export', '--format', '3dgs', '--scene', args.scene,
                                            '--unlit', '--size', args.size, '--out', ply,
                                            '--preview', path.join(work, 'twin.png'),
                                            '--mapping', args.mapping || 'coverage']);
const splatCount = Number(/count\s+(\d+)/.exec(spotshell(args.spotshell, ['info', '--splats', ply]))[1]);
const reference = path.join(work, 'spotshell.png');
spotshell(args.spotshell, ['render', '--scene', args.scene, '--unlit', '--method', 'reference', '--size',
                           args.size, '--out', reference]);

// The scene's background (linear) as display values, for the viewer's clear colour.
const scene = JSON.parse(fs.readFileSync(args.scene, 'utf8'));
const encode = (x) => (x <= 0.0031308 ? 12.92 * x : 1.055 * Math.pow(x, 1 / 2.4) - 0.055);
const bg = (scene.background || [0, 0, 0]).map(encode).join(',');

const files = {
    '/': [path.join(here, 'viewer.html'), 'text/html'],
    '/splats.ply': [ply, 'application/octet-stream'],
    '/cameras.json': [path.join(work, 'cameras.json'), 'application/json'],
};
const roots = { '/three/': path.join(modules, 'three'),
                '/gs3d/': path.join(modules, '@mkkellogg/gaussian-splats-3d') };
const picture = path.join(work, 'viewer.png');
let browser = null;
let timer = null;
const finish = (message) => {
    clearTimeout(timer);
    if (browser && browser.exitCode === null)
        browser.kill('SIGKILL');
    server.close();
    if (message)
        fail(message);
};
const server = http.createServer((req, res) => {
    const url = new URL(req.url, 'http://localhost');
    if (req.method === 'POST') {
        const chunks = [];
        req.on('data', (c) => chunks.push(c));
        req.on('end', () => {
            res.end();
            const body = Buffer.concat(chunks).toString('latin1');
            if (url.pathname === '/error')
                return finish(`the viewer failed: ${body}`);
            const drawn = Number(url.searchParams.get('count'));
            fs.writeFileSync(picture, Buffer.from(body.replace(/^data:image\/png;base64,/, ''), 'base64'));
            finish();
            if (drawn !== splatCount)
                fail(`the viewer loaded ${drawn} splats of ${splatCount}`);
            const viewerPsnr = psnr(args.spotshell, reference, picture);
            const twinPsnr = psnr(args.spotshell, reference, path.join(work, 'twin.png'));
            console.log(`${exported.trim().split('\n')[0]}`);
            console.log(`viewer (${drawn} splats) against spotshell's reference: ${viewerPsnr.toFixed(2)} dB ` +
                        `(floor ${args.floor}); spotshell's CPU twin of a 3DGS rasteriser: ` +
                        `${twinPsnr.toFixed(2)} dB; viewer against the twin: ` +
                        `${psnr(args.spotshell, path.join(work, 'twin.png'), picture).toFixed(2)} dB`);
            console.log(`pictures: ${reference} ${picture}`);
            if (!(viewerPsnr >= Number(args.floor)))
                fail(`the viewer's picture is ${viewerPsnr} dB from spotshell's, below ${args.floor}`);
        });
        return;
    }
    let file = files[url.pathname];
    for (const [prefix, root] of Object.entries(roots))
        if (!file && url.pathname.startsWith(prefix)) {
            const resolved = path.join(root, path.normalize(url.pathname.slice(prefix.length)));
            if (resolved.startsWith(root))
                file = [resolved, resolved.endsWith('.js') ? 'text/javascript' : 'application/octet-stream'];
        }
    if (!file || !fs.existsSync(file[0])) {
        res.writeHead(404);
        return res.end();
    }
    res.writeHead(200, { 'Content-Type': file[1] });
    fs.createReadStream(file[0]).pipe(res);
});
server.listen(0, '127.0.0.1', () => {
    const [w, h] = args.size.split('x');
    const profile = path.join(work, 'chromium-profile');
    fs.rmSync(profile, { recursive: true, force: true });
    browser = spawn(args.chromium || 'chromium', [
        '--headless=new', '--no-sandbox', '--no-first-run', '--disable-extensions',
        '--disable-dev-shm-usage',
        '--use-angle=swiftshader', '--enable-unsafe-swiftshader', '--ignore-gpu-blocklist',
        `--user-data-dir=${profile}`, `--window-size=${w},${h}`,
        `http://127.0.0.1:${server.address().port}/?bg=${bg}`], { stdio: ['ignore', 'ignore', 'pipe'] });
    let log = '';
    browser.stderr.on('data', (d) => { log = (log + d).slice(-4000); });
    browser.on('error', (e) => finish(`cannot start chromium: ${e.message}`));
    timer = setTimeout(() => finish(`no picture from the viewer after 100 s; chromium said: ${log}`), 100000);
});
