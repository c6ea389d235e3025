// A client of benchmarks/bench_bridge.py in Node: roslibjs (npm `roslib`) or Foxglove's fork
// (`@foxglove/roslibjs`), both over `ws`.  It speaks the driver's protocol: one JSON line "ready", then for
// each command line on stdin (`small`, `image_json`, `image_cbor`, `rtt N`, `end`) one JSON line of figures,
// stamped as the Python clients stamp them: wall clock and process CPU (user+sys, every thread) at the first
// and at the last message of a flood.
//
// usage: node bench_client.mjs --lib roslib|foxglove --url ws://127.0.0.1:PORT --sizes '{"small": ...}'

import { createRequire } from "node:module";
import { performance } from "node:perf_hooks";
import readline from "node:readline";

const args = Object.fromEntries(process.argv.slice(2).reduce((acc, v, i, a) => {
  if (v.startsWith("--")) acc.push([v.slice(2), a[i + 1]]);
  return acc;
}, []));
const n = JSON.parse(args.sizes);
const say = (obj) => process.stdout.write(JSON.stringify(obj) + "\n");
const cpu = () => { const u = process.cpuUsage(); return (u.user + u.system) / 1e6; };
const now = () => performance.now() / 1e3;

async function load(lib) {
  if (lib === "roslib") {
    const R = await import("roslib");
    return { Ros: R.Ros, Topic: R.Topic, message: (m) => m };
  }
  const require = createRequire(import.meta.url);
  const R = require("@foxglove/roslibjs/src/RosLib.js");
  return { Ros: R.Ros, Topic: R.Topic, message: (m) => new R.Message(m) };
}

const L = await load(args.lib);
const ros = new L.Ros({ url: args.url });
await new Promise((resolve, reject) => {
  ros.on("connection", resolve);
  ros.on("error", reject);
});

function ingest(name, type, count, compression) {
  return new Promise((resolve) => {
    let k = 0, t0 = 0, c0 = 0;
    const topic = new L.Topic({ ros, name, messageType: type, compression });
    topic.subscribe(() => {
      k += 1;
      if (k === 1) { t0 = now(); c0 = cpu(); }
      else if (k === count) {
        const t1 = now(), c1 = cpu();
        topic.unsubscribe();
        resolve({ n: count - 1, wall_s: t1 - t0, cpu_s: c1 - c0 });
      }
    });
  });
}

const ping = new L.Topic({ ros, name: "/bench/ping", messageType: "std_msgs/Float64" });
ping.advertise();
const pong = new L.Topic({ ros, name: "/bench/pong", messageType: "std_msgs/Float64" });
let waiting = null;
pong.subscribe((msg) => {
  if (waiting && msg.data === waiting.want) { const w = waiting; waiting = null; w.resolve(now()); }
});
await new Promise((r) => setTimeout(r, 300));

let seq = 0;
function trip() {  // resolves with the time the echo arrived
  seq += 1;
  const want = seq;
  return new Promise((resolve) => {
    waiting = { want, resolve };
    ping.publish(L.message({ data: want }));
  });
}

async function block(count, warmup = 5) {
  for (let i = 0; i < warmup; i++) await timedTrip();
  const samples = [];
  const c0 = cpu();
  for (let i = 0; i < count; i++) samples.push(await timedTrip());
  return { samples, cpu_s: cpu() - c0 };
}

async function timedTrip() {
  const t0 = now();
  const t1 = await trip();
  return t1 - t0;
}

await block(0, n.rtt_warmup);
const commands = {
  small: () => ingest("/bench/f64", "std_msgs/Float64", n.small, "none"),
  image_json: () => ingest("/bench/image", "sensor_msgs/Image", n.image_json, "none"),
  image_cbor: () => ingest("/bench/image", "sensor_msgs/Image", n.image_cbor, "cbor"),
  rtt: (count) => block(Number(count)),
};

say({ ready: true });
const rl = readline.createInterface({ input: process.stdin });
for await (const line of rl) {
  const words = line.trim().split(/\s+/);
  if (!words[0] || words[0] === "end") break;
  say(await commands[words[0]](...words.slice(1)));
}
say({ peak_rss_mb: process.resourceUsage().maxRSS / 1024 });
process.exit(0);
