// The viewer protocol (docs/viewer-protocol.md), page side: the binary pose frame read
// and checked, and the socket with its page messages. Knows nothing of three.js, so
// Node can test it on hand-made frames (tests/web/protocol_test.mjs).

export const kFrameVersion = 1;
export const kFrameHeaderBytes = 24;
export const kTargetRecordBytes = 16;
/** Bytes of one avatar's record: its root (3 f32) and J joint offsets (3 i16 each). */
export const avatarRecordBytes = (joints) => 12 + 6 * joints;

// 'MGRF' as the four bytes the server writes.
const kMagic = [0x4d, 0x47, 0x52, 0x46];

/**
 * One binary pose frame, checked on construction: throws an Error that says what was
 * expected and what was found when the magic, the version, the joint count (when
 * `expectedJoints` is given) or the byte size disagree with the header.
 * Reads lazily: a page that is sent frames faster than it draws decodes only the ones
 * it draws.
 */
export class PoseFrame {
  constructor(buffer, expectedJoints) {
    if (!(buffer instanceof ArrayBuffer)) throw new Error('pose frame: expected an ArrayBuffer');
    if (buffer.byteLength < kFrameHeaderBytes) {
      throw new Error(`pose frame: expected at least ${kFrameHeaderBytes} bytes, found ${buffer.byteLength}`);
    }
    const view = new DataView(buffer);
    for (let i = 0; i < 4; ++i) {
      if (view.getUint8(i) !== kMagic[i]) {
        const found = Array.from(new Uint8Array(buffer, 0, 4), (b) => b.toString(16).padStart(2, '0')).join(' ');
        throw new Error(`pose frame: expected magic 'MGRF', found bytes ${found}`);
      }
    }
    const version = view.getUint16(4, true);
    if (version !== kFrameVersion) {
      throw new Error(`pose frame: expected version ${kFrameVersion}, found ${version}`);
    }
    this.joints = view.getUint16(6, true);
    this.avatars = view.getUint32(8, true);
    this.targets = view.getUint32(12, true);
    this.frame = view.getUint32(16, true);
    this.time = view.getFloat32(20, true);
    if (expectedJoints !== undefined && this.joints !== expectedJoints) {
      throw new Error(`pose frame: expected ${expectedJoints} joints per avatar (scene), found ${this.joints}`);
    }
    this.recordBytes = avatarRecordBytes(this.joints);
    this.targetsOffset = kFrameHeaderBytes + this.avatars * this.recordBytes;
    const expectedBytes = this.targetsOffset + this.targets * kTargetRecordBytes;
    if (buffer.byteLength !== expectedBytes) {
      throw new Error(`pose frame: expected ${expectedBytes} bytes for ${this.avatars} avatars of ` +
                      `${this.joints} joints and ${this.targets} targets, found ${buffer.byteLength}`);
    }
    this.byteLength = buffer.byteLength;
    this.view = view;
  }

  /** Avatar i's root joint, world metres, as [x, y, z]; null when out of range. */
  root(i) {
    if (!(i >= 0 && i < this.avatars)) return null;
    const at = kFrameHeaderBytes + i * this.recordBytes;
    const v = this.view;
    return [v.getFloat32(at, true), v.getFloat32(at + 4, true), v.getFloat32(at + 8, true)];
  }

  /**
   * Every joint of every avatar in world metres into `out` (a Float32Array of at least
   * avatars * joints * 3, avatar-major, joint order of `scene.joints`).
   */
  jointPositions(out) {
    const v = this.view;
    const J = this.joints;
    let k = 0;
    for (let i = 0; i < this.avatars; ++i) {
      let at = kFrameHeaderBytes + i * this.recordBytes;
      const x = v.getFloat32(at, true), y = v.getFloat32(at + 4, true), z = v.getFloat32(at + 8, true);
      at += 12;
      for (let j = 0; j < J; ++j, at += 6) {
        out[k++] = x + v.getInt16(at, true) * 0.001;
        out[k++] = y + v.getInt16(at + 2, true) * 0.001;
        out[k++] = z + v.getInt16(at + 4, true) * 0.001;
      }
    }
  }

  /** Target record r as {avatar, centre: [x, y, z]} (world metres, bend included). */
  targetRecord(r) {
    const at = this.targetsOffset + r * kTargetRecordBytes;
    const v = this.view;
    return {
      avatar: v.getUint32(at, true),
      centre: [v.getFloat32(at + 4, true), v.getFloat32(at + 8, true), v.getFloat32(at + 12, true)],
    };
  }

  /** The centre of avatar i's own target, or null when it has none. */
  targetOf(i) {
    for (let r = 0; r < this.targets; ++r) {
      const record = this.targetRecord(r);
      if (record.avatar === i) return record.centre;
    }
    return null;
  }
}

/**
 * Limits the rate of one kind of message (a slider sends on every pixel): sends at once
 * when the last send is older than `intervalMs`, otherwise keeps the newest message and
 * sends it when the interval is up, so the last value always arrives.
 */
export function throttled(send, intervalMs) {
  let last = -Infinity;
  let pending = null;
  let timer = null;
  const flush = () => {
    timer = null;
    if (pending === null) return;
    const message = pending;
    pending = null;
    last = performance.now();
    send(message);
  };
  const throttledSend = (message) => {
    pending = message;
    if (timer !== null) return;
    const wait = last + intervalMs - performance.now();
    if (wait <= 0) flush();
    else timer = setTimeout(flush, wait);
  };
  throttledSend.flush = () => {
    if (timer !== null) clearTimeout(timer);
    flush();
  };
  return throttledSend;
}

/**
 * The page's WebSocket to `mgrl serve`: text messages are JSON objects dispatched by
 * `type`, binary ones are pose frames. Reconnects after a close (the server may have
 * restarted), with a growing pause.
 */
export class Connection {
  /**
   * @param url       ws://host/ws
   * @param handlers  {message(obj), frame(ArrayBuffer), open(), close(reason)}
   */
  constructor(url, handlers) {
    this.url = url;
    this.handlers = handlers;
    this.socket = null;
    this.retryMs = 500;
    this.open();
  }

  open() {
    const socket = new WebSocket(this.url);
    socket.binaryType = 'arraybuffer';
    this.socket = socket;
    socket.onopen = () => {
      this.retryMs = 500;
      this.handlers.open?.();
    };
    socket.onmessage = (event) => {
      if (typeof event.data !== 'string') {
        this.handlers.frame(event.data);
        return;
      }
      let message;
      try {
        message = JSON.parse(event.data);
      } catch (e) {
        console.warn(`mgrl: ignored a text message that is not JSON: ${e.message}`);
        return;
      }
      if (message === null || typeof message !== 'object' || typeof message.type !== 'string') {
        console.warn('mgrl: ignored a text message without a "type"');
        return;
      }
      this.handlers.message(message);
    };
    socket.onclose = (event) => {
      this.handlers.close?.(`closed (code ${event.code}${event.reason ? ': ' + event.reason : ''})`);
      setTimeout(() => this.open(), this.retryMs);
      this.retryMs = Math.min(this.retryMs * 2, 8000);
    };
  }

  /** Sends one page message (an object, as JSON); false when the socket is not open. */
  send(message) {
    if (this.socket === null || this.socket.readyState !== WebSocket.OPEN) return false;
    this.socket.send(JSON.stringify(message));
    return true;
  }
}
