// The page's connection to the service: gRPC-web calls on the page's own origin, the world
// stream (`Join` in the patch form, with presence) re-joined with backoff, and the unary
// calls with the session's token.
import { create, toBinary } from "@bufbuild/protobuf";
import { Code, ConnectError, createClient } from "@connectrpc/connect";
import type { Client } from "@connectrpc/connect";
import { createGrpcWebTransport } from "@connectrpc/connect-web";
import { DeltaForm, JoinRequestSchema, WorldMessageSchema, WorldService } from "./gen/naadf/v1/naadf_pb";
import type { Page, PresenceEntry, StatusReply, WorldMessage } from "./gen/naadf/v1/naadf_pb";
import { PROTOCOL_VERSION } from "./gen/layout";
import type { PageCache } from "./cache";
import { Mirror, MirrorError } from "./mirror";
import type { Touched } from "./mirror";

/** Where the session is. */
export type SessionState = "connecting" | "need-token" | "syncing" | "live" | "reconnecting" | "error";

/** What the session tells the page. */
export interface SessionEvents {
  state(s: SessionState, why?: string): void;
  /** A `Join` stream was opened. */
  joined(): void;
  /** A snapshot completed: the whole world is new. */
  snapshot(m: Mirror): void;
  /** The world was rebuilt from the page's cache (before joining). */
  restored(m: Mirror): void;
  /** A delta was applied. */
  patched(m: Mirror, touched: Touched[], resized: boolean): void;
  presence(entries: PresenceEntry[]): void;
}

/** The key of the token in `sessionStorage` (never in a URL). */
const TOKEN_KEY = "naadf.token";

/** The first wait before joining again, and the longest. */
const FIRST_BACKOFF_MS = 100;
const MOST_BACKOFF_MS = 5000;

/** The page's session with the server that served it. */
export class Session {
  readonly mirror = new Mirror();
  readonly client: Client<typeof WorldService>;
  /** Bytes of world messages received, as the native mirror counts them. */
  bytesReceived = 0;
  /** Bytes of the last snapshot or resume: its header and pages. */
  snapshotBytes = 0;
  private abort: AbortController | undefined;
  private stopped = false;
  private saving: ReturnType<typeof setTimeout> | undefined;

  constructor(
    private readonly events: SessionEvents,
    private readonly cache: PageCache | undefined,
  ) {
    this.client = createClient(WorldService, createGrpcWebTransport({ baseUrl: location.origin, useBinaryFormat: true }));
  }

  /** The token this tab holds, if any. */
  static token(): string | null {
    return sessionStorage.getItem(TOKEN_KEY);
  }

  /** Keeps `token` for this tab and joins again with it. */
  setToken(token: string): void {
    sessionStorage.setItem(TOKEN_KEY, token);
    this.restart();
  }

  /** The call options with the token. */
  callOptions(): { headers: Record<string, string> } {
    const t = Session.token();
    return { headers: t ? { authorization: `Bearer ${t}` } : {} };
  }

  /** Who the server takes this page for. */
  async whoAmI(): Promise<StatusReply> {
    return this.client.status({}, this.callOptions());
  }

  /** Rebuilds the world from the cache, if it holds one; whether it did. */
  async restore(): Promise<boolean> {
    if (!this.cache || !(await this.cache.restore(this.mirror).catch(() => false))) return false;
    this.events.restored(this.mirror);
    return true;
  }

  /** Saves the world to the cache soon (coalescing a burst of deltas). */
  private saveSoon(): void {
    if (!this.cache || this.saving) return;
    this.saving = setTimeout(() => {
      this.saving = undefined;
      this.cache?.save(this.mirror).catch((e) => console.warn(`the page cache: ${e}`));
    }, 1000);
  }

  /** Joins, and joins again whenever the stream ends, until a refusal that a person must
   * act on (a token) or `stop`. */
  async run(): Promise<void> {
    let backoff = FIRST_BACKOFF_MS;
    let first = true;
    while (!this.stopped) {
      this.events.state(first ? "connecting" : "reconnecting");
      first = false;
      this.abort = new AbortController();
      try {
        const gotMessages = await this.follow(this.abort.signal);
        if (gotMessages) backoff = FIRST_BACKOFF_MS;
      } catch (e) {
        if (e instanceof MirrorError) {
          // Diverged or refused data: join again announcing what is held.
          console.warn(e.message);
        } else {
          const err = ConnectError.from(e);
          if (err.code === Code.Unauthenticated || err.code === Code.PermissionDenied) {
            this.events.state("need-token", err.rawMessage);
            return;
          }
          if (err.code === Code.FailedPrecondition) {
            this.events.state("error", err.rawMessage);
            return;
          }
          if (err.code === Code.Canceled && this.stopped) return;
          if (err.code !== Code.Canceled) console.warn(`the world stream ended: ${err.message}`);
        }
      }
      if (this.stopped) return;
      this.events.state("reconnecting");
      const wait = backoff * (1 + Math.random() / 4);
      backoff = Math.min(MOST_BACKOFF_MS, backoff * 2);
      await new Promise((r) => setTimeout(r, wait));
    }
  }

  /** Ends the current stream; `run` joins again at once. */
  restart(): void {
    this.abort?.abort();
  }

  /** Follows one `Join` stream until it ends; returns whether any message came. */
  private async follow(signal: AbortSignal): Promise<boolean> {
    const m = this.mirror;
    const request = create(JoinRequestSchema, {
      protocolVersion: PROTOCOL_VERSION,
      cached: m.cached(),
      resume: m.holdsWorld ? { version: m.version, digest: m.digest } : undefined,
      deltaForm: DeltaForm.PATCH,
      presence: true,
    });
    let any = false;
    this.events.joined();
    for await (const msg of this.client.join(request, { ...this.callOptions(), signal })) {
      any = true;
      const bytes = encodedLength(msg);
      this.bytesReceived += bytes;
      const k = msg.kind;
      if (k.case === "header") this.snapshotBytes = 0;
      if (k.case === "header" || k.case === "page") this.snapshotBytes += bytes;
      switch (k.case) {
        case "header": {
          this.events.state("syncing");
          if (!m.header(k.value)) this.live(k.value.resume);
          break;
        }
        case "page":
          if (m.page(k.value)) this.live(false);
          break;
        case "delta": {
          const { touched, resized } = m.delta(k.value);
          this.events.patched(m, touched, resized);
          this.saveSoon();
          break;
        }
        case "presence":
          this.events.presence(k.value.entries);
          break;
      }
    }
    return any;
  }

  private live(resumed: boolean): void {
    if (!resumed) this.events.snapshot(this.mirror);
    this.saveSoon();
    this.events.state("live");
  }
}

/** Bytes of a varint. */
const varintLength = (n: number) => (n < 0x80 ? 1 : n < 0x4000 ? 2 : n < 0x200000 ? 3 : n < 0x10000000 ? 4 : 5);

/** A field's tag and length prefix, and its bytes. */
const lengthDelimited = (n: number) => 1 + varintLength(n) + n;

/** The encoded size of a stream message, as the native mirror counts its bytes: pages
 * (nearly all of a snapshot) computed from their fields, the rest encoded. */
function encodedLength(msg: WorldMessage): number {
  if (msg.kind.case !== "page") return toBinary(WorldMessageSchema, msg).length;
  const p: Page = msg.kind.value;
  const indices = p.indices.reduce((a, i) => a + varintLength(i), 0);
  const inner =
    (p.buffer ? 1 + varintLength(p.buffer) : 0) + (p.indices.length ? lengthDelimited(indices) : 0) + (p.zstd.length ? lengthDelimited(p.zstd.length) : 0);
  return lengthDelimited(inner);
}
