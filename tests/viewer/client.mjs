// A viewer's side of the Foxglove WebSocket protocol, spoken by the npm package
// @foxglove/ws-protocol (its FoxgloveClient asks for the subprotocol foxglove.websocket.v1,
// as Lichtblick and Foxglove releases before the SDK do), against `landscape view`.
//   node client.mjs URL TOPIC ASSET_URI
// Prints one JSON line: the subprotocol the server chose, its serverInfo name, the
// advertised topics, the first message of TOPIC (as text) and the asset's size; exit 1
// with the reason when any of them does not come within 10 s.
import wsProtocol from "@foxglove/ws-protocol";
import WebSocket from "ws";

const { FoxgloveClient } = wsProtocol;

const [url, topic, assetUri] = process.argv.slice(2);
const ws = new WebSocket(url, [FoxgloveClient.SUPPORTED_SUBPROTOCOL]);
const client = new FoxgloveClient({ ws });
const got = { subprotocol: null, server: null, topics: [], message: null, asset_bytes: null };
const decoder = new TextDecoder();
let subscription = null;

const fail = (why) => {
  console.error(`client: ${why}`);
  process.exit(1);
};
const timer = setTimeout(() => fail(`timed out with ${JSON.stringify(got)}`), 10000);
const done = () => {
  if (got.message !== null && got.asset_bytes !== null) {
    clearTimeout(timer);
    console.log(JSON.stringify(got));
    client.close();
    process.exit(0);
  }
};

client.on("open", () => {
  got.subprotocol = ws.protocol;
});
client.on("error", (err) => fail(`error: ${err.message ?? err}`));
client.on("close", (ev) => fail(`closed (${ev.code ?? "?"}) with ${JSON.stringify(got)}`));
client.on("serverInfo", (info) => {
  got.server = info.name;
  client.fetchAsset(assetUri, 1);
});
client.on("advertise", (channels) => {
  for (const ch of channels) {
    got.topics.push(ch.topic);
    if (ch.topic === topic && subscription === null) {
      subscription = client.subscribe(ch.id);
    }
  }
});
client.on("message", (msg) => {
  if (msg.subscriptionId === subscription && got.message === null) {
    got.message = decoder.decode(msg.data);
    done();
  }
});
client.on("fetchAssetResponse", (res) => {
  if (res.status !== 0) fail(`asset ${assetUri}: ${res.error}`);
  got.asset_bytes = res.data.byteLength;
  done();
});
