// Drives cwloc-serve's map viewer (serve/viewer/) in headless Chromium: the page loads the map,
// a photo goes through its file input to POST /v1/localize, and the pose it draws must be the
// one the same server gave curl for the same photo.
//
//   node viewer_browser_test.mjs --server URL --photo PATH --expected-json FILE --screenshot OUT.png
//        [--chromium /usr/bin/chromium]
//
// FILE is the record of `curl -F image=@PATH URL/v1/localize?index=...` (the default index).
// Exit status: 0 passed, 1 failed (with the reason), 77 skipped (no Chromium, or no
// puppeteer-core: `npm ci` in tests/serve). Finishes within 60 s, whatever happens.
import { accessSync, constants, mkdirSync, readFileSync } from 'node:fs';
import { dirname, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';

const TOTAL_BUDGET_MS = 55000;  // under the harness's 60 s, with room to close Chromium
const started = Date.now();
const here = dirname(fileURLToPath(import.meta.url));

// WebGL in headless Chromium runs on SwiftShader (ANGLE on Vulkan). Chromium 156 refuses that
// software fallback unless --enable-unsafe-swiftshader is given (it warns, then will stop);
// --use-angle=swiftshader asks for it outright. (--use-gl=swiftshader leaves no WebGL at all.)
const CHROMIUM_FLAGS = [
  '--no-sandbox',  // CI runs as root, where Chromium's sandbox cannot start
  '--use-angle=swiftshader',
  '--enable-unsafe-swiftshader',
  '--disable-dev-shm-usage',  // containers often have a small /dev/shm
  '--window-size=1280,800',
];

let browser = null;

function finish(code, message) {
  const seconds = ((Date.now() - started) / 1000).toFixed(1);
  if (message) (code === 0 ? console.log : console.error)(`${message} (${seconds} s)`);
  const closing = browser ? browser.close().catch(() => {}) : Promise.resolve();
  browser = null;
  // Chromium must not outlive the test, even when it does not close in time.
  Promise.race([closing, new Promise((r) => setTimeout(r, 3000))]).then(() => process.exit(code));
}

const fail = (message) => finish(1, `FAIL: ${message}`);

const watchdog = setTimeout(() => {
  const process_ = browser && browser.process();
  if (process_) process_.kill('SIGKILL');
  browser = null;
  fail(`timed out after ${TOTAL_BUDGET_MS / 1000} s`);
}, TOTAL_BUDGET_MS);

// Time left for one step, so that no step can overrun the whole test's budget.
const left = (wanted) => Math.max(1000, Math.min(wanted, TOTAL_BUDGET_MS - (Date.now() - started) - 2000));

function parseArguments(argv) {
  const args = { chromium: '/usr/bin/chromium' };
  const names = { '--server': 'server', '--photo': 'photo', '--expected-json': 'expected', '--screenshot': 'screenshot', '--chromium': 'chromium' };
  for (let i = 0; i < argv.length; i += 2) {
    const name = names[argv[i]];
    if (!name || i + 1 >= argv.length) throw new Error(`unknown or incomplete argument '${argv[i]}'`);
    args[name] = argv[i + 1];
  }
  for (const name of ['server', 'photo', 'expected', 'screenshot']) {
    if (!args[name]) throw new Error('usage: node viewer_browser_test.mjs --server URL --photo PATH --expected-json FILE --screenshot OUT.png');
  }
  return args;
}

// Counts the pixels of a PNG (a screenshot) near a colour, decoding it in the page: Node has no
// PNG decoder without more packages.
async function countColour(page, pngBase64, [r, g, b], tolerance) {
  return page.evaluate(async (data, rgb, tol) => {
    const image = new Image();
    image.src = 'data:image/png;base64,' + data;
    await image.decode();
    const canvas = document.createElement('canvas');
    canvas.width = image.width;
    canvas.height = image.height;
    const context = canvas.getContext('2d');
    context.drawImage(image, 0, 0);
    const pixels = context.getImageData(0, 0, canvas.width, canvas.height).data;
    let count = 0;
    for (let i = 0; i < pixels.length; i += 4) {
      if (Math.abs(pixels[i] - rgb[0]) <= tol && Math.abs(pixels[i + 1] - rgb[1]) <= tol && Math.abs(pixels[i + 2] - rgb[2]) <= tol) count++;
    }
    return count;
  }, pngBase64, [r, g, b], tolerance);
}

async function main() {
  let args;
  try {
    args = parseArguments(process.argv.slice(2));
  } catch (e) {
    return fail(e.message);
  }
  try {
    accessSync(args.chromium, constants.X_OK);
  } catch (e) {
    return finish(77, `skipped: no Chromium at ${args.chromium}`);
  }
  let puppeteer;
  try {
    puppeteer = (await import('puppeteer-core')).default;
  } catch (e) {
    return finish(77, `skipped: puppeteer-core not installed (cd ${here} && PUPPETEER_SKIP_DOWNLOAD=1 npm ci)`);
  }

  let expected;
  try {
    expected = JSON.parse(readFileSync(args.expected, 'utf8'));
  } catch (e) {
    return fail(`cannot read the expected record ${args.expected}: ${e.message}`);
  }
  if (!expected.success || !expected.pose || !Array.isArray(expected.pose.center)) {
    return fail(`the expected record did not localize (${expected.failure_reason || expected.error || 'no pose'}); the test needs a photo that does`);
  }

  browser = await puppeteer.launch({
    executablePath: args.chromium,
    headless: true,
    args: CHROMIUM_FLAGS,
    defaultViewport: { width: 1280, height: 800 },
    timeout: left(20000),
    protocolTimeout: left(30000),
  });
  const page = await browser.newPage();
  page.setDefaultTimeout(left(30000));
  const pageErrors = [];
  page.on('pageerror', (error) => pageErrors.push(error.message));
  page.on('console', (message) => {
    if (message.type() === 'error') pageErrors.push(`console: ${message.text()}`);
  });

  try {
    await page.goto(args.server, { waitUntil: 'load', timeout: left(20000) });
  } catch (e) {
    return fail(`cannot open ${args.server}: ${e.message}`);
  }
  const webgl = await page.evaluate(() => {
    const canvas = document.querySelector('#view canvas');
    const gl = canvas && (canvas.getContext('webgl') || canvas.getContext('experimental-webgl'));
    if (!gl) return null;
    const info = gl.getExtension('WEBGL_debug_renderer_info');
    return String(gl.getParameter(info ? info.UNMASKED_RENDERER_WEBGL : gl.RENDERER));
  });
  if (!webgl) return fail(`no WebGL in headless Chromium (flags: ${CHROMIUM_FLAGS.join(' ')}); page errors: ${pageErrors.join('; ') || 'none'}`);

  await page.waitForFunction(() => ['loaded', 'error'].includes(document.body.dataset.map), { timeout: left(20000) });
  const status = () => page.$eval('#status', (node) => node.textContent);
  if (await page.evaluate(() => document.body.dataset.map) !== 'loaded') {
    return fail(`the map did not load: ${await status()}`);
  }

  // The pose's frustum is orange (#ff7a1a); before it, only the legend's swatch is.
  const ORANGE = [0xff, 0x7a, 0x1a];
  const orangeBefore = await countColour(page, Buffer.from(await page.screenshot({ type: 'png' })).toString('base64'), ORANGE, 40);

  const input = await page.$('#photo-input');
  if (!input) return fail('the page has no #photo-input');
  await input.uploadFile(resolve(args.photo));
  await page.waitForFunction(() => ['posed', 'failed', 'error'].includes(document.body.dataset.state), { timeout: left(40000) });
  const state = await page.evaluate(() => document.body.dataset.state);
  if (state !== 'posed') {
    const reason = await page.evaluate(() => window.cwlocLastResult && window.cwlocLastResult.failure_reason);
    return fail(`the page's state is '${state}', not 'posed': ${reason || await status()}`);
  }

  const shown = await page.evaluate(() => ({
    record: window.cwlocLastResult,
    centerText: document.getElementById('pose-center') && document.getElementById('pose-center').textContent,
    inliersText: document.getElementById('num-inliers') && document.getElementById('num-inliers').textContent,
  }));
  const problems = [];
  const center = shown.record && shown.record.pose && shown.record.pose.center;
  let maxDifference = Infinity;
  if (!Array.isArray(center) || center.length !== 3) {
    problems.push('window.cwlocLastResult has no pose.center');
  } else {
    maxDifference = Math.max(...center.map((x, k) => Math.abs(x - expected.pose.center[k])));
    if (!(maxDifference <= 1e-9)) {
      problems.push(`pose.center ${center.join(' ')} differs from the expected ${expected.pose.center.join(' ')} by ${maxDifference}`);
    }
  }
  const expectedText = expected.pose.center.map((x) => x.toFixed(6)).join(' ');
  if (shown.centerText !== expectedText) problems.push(`#pose-center shows '${shown.centerText}', expected '${expectedText}'`);
  if (shown.record && shown.record.num_inliers !== expected.num_inliers) {
    problems.push(`window.cwlocLastResult.num_inliers is ${shown.record.num_inliers}, expected ${expected.num_inliers}`);
  }
  if (shown.inliersText !== String(expected.num_inliers)) {
    problems.push(`the page shows ${shown.inliersText} inliers, expected ${expected.num_inliers}`);
  }

  // The screenshot, and a look at it: the pose's frustum must have been drawn.
  mkdirSync(dirname(resolve(args.screenshot)), { recursive: true });
  const png = await page.screenshot({ path: args.screenshot, type: 'png' });
  const orange = await countColour(page, Buffer.from(png).toString('base64'), ORANGE, 40) - orangeBefore;
  if (orange < 50) problems.push(`the screenshot shows no pose frustum (${orange} more orange pixels than before): is WebGL drawing?`);
  if (pageErrors.length) problems.push(`errors in the page: ${pageErrors.join('; ')}`);

  if (problems.length) return fail(problems.join('\n  '));
  return finish(0, `PASS: ${expected.name || args.photo}: centre ${expectedText} (max difference ${maxDifference}), ` +
    `${expected.num_inliers} inliers, ${orange} pose pixels; WebGL: ${webgl}; screenshot ${args.screenshot}`);
}

main().catch((e) => fail(e && e.stack ? e.stack : String(e))).finally(() => clearTimeout(watchdog));
