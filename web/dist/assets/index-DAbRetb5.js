function e(e,t){return typeof e==`object`&&e&&`$typeName`in e&&typeof e.$typeName==`string`?t===void 0||t.typeName===e.$typeName:!1}var t;(function(e){e[e.DOUBLE=1]=`DOUBLE`,e[e.FLOAT=2]=`FLOAT`,e[e.INT64=3]=`INT64`,e[e.UINT64=4]=`UINT64`,e[e.INT32=5]=`INT32`,e[e.FIXED64=6]=`FIXED64`,e[e.FIXED32=7]=`FIXED32`,e[e.BOOL=8]=`BOOL`,e[e.STRING=9]=`STRING`,e[e.BYTES=12]=`BYTES`,e[e.UINT32=13]=`UINT32`,e[e.SFIXED32=15]=`SFIXED32`,e[e.SFIXED64=16]=`SFIXED64`,e[e.SINT32=17]=`SINT32`,e[e.SINT64=18]=`SINT64`})(t||={});function n(){let e=this.buf,t=this.pos,n=0,r=0;for(let i=0;i<28;i+=7){let a=e[t++];if(n|=(a&127)<<i,!(a&128)){this.pos=t,this.assertBounds(),this.varint64Lo=n,this.varint64Hi=r;return}}let i=e[t++];if(n|=(i&15)<<28,r=(i&112)>>4,!(i&128))this.pos=t,this.assertBounds(),this.varint64Lo=n,this.varint64Hi=r;else{for(let i=3;i<=31;i+=7){let a=e[t++];if(r|=(a&127)<<i,!(a&128)){this.pos=t,this.assertBounds(),this.varint64Lo=n,this.varint64Hi=r;return}}throw Error(`invalid varint`)}}var r=4294967296;function i(e){let t=e[0]===`-`;t&&(e=e.slice(1));let n=1e6,i=0,a=0;function o(t,o){let s=Number(e.slice(t,o));a*=n,i=i*n+s,i>=r&&(a+=i/r|0,i%=r)}return o(-24,-18),o(-18,-12),o(-12,-6),o(-6),t?l(i,a):c(i,a)}function a(e,t){let n=c(e,t),r=n.hi&0x80000000;r&&(n=l(n.lo,n.hi));let i=o(n.lo,n.hi);return r?`-`+i:i}function o(e,t){if({lo:e,hi:t}=s(e,t),t<=2097151)return String(r*t+e);let n=e&0xffffff,i=(e>>>24|t<<8)&0xffffff,a=t>>16&65535,o=n+i*6777216+a*6710656,c=i+a*8147497,l=a*2,d=1e7;return o>=d&&(c+=Math.floor(o/d),o%=d),c>=d&&(l+=Math.floor(c/d),c%=d),l.toString()+u(c)+u(o)}function s(e,t){return{lo:e>>>0,hi:t>>>0}}function c(e,t){return{lo:e|0,hi:t|0}}function l(e,t){return t=~t,e?e=~e+1:t+=1,c(e,t)}var u=e=>{let t=String(e);return`0000000`.slice(t.length)+t};function d(e,t){if(e>>>0<128)t.push(e);else if(e>=0){for(;e>127;)t.push(e&127|128),e>>>=7;t.push(e)}else{for(let n=0;n<9;n++)t.push(e&127|128),e>>=7;t.push(1)}}function f(){let e=this.buf[this.pos++];if(!(e&128))return this.assertBounds(),e;let t=e&127;if(e=this.buf[this.pos++],t|=(e&127)<<7,!(e&128)||(e=this.buf[this.pos++],t|=(e&127)<<14,!(e&128))||(e=this.buf[this.pos++],t|=(e&127)<<21,!(e&128)))return this.assertBounds(),t;e=this.buf[this.pos++],t|=(e&15)<<28;for(let t=5;e&128&&t<10;t++)e=this.buf[this.pos++];if(e&128)throw Error(`invalid varint`);return this.assertBounds(),t>>>0}var p=m();function m(){let e=new DataView(new ArrayBuffer(8));if(typeof BigInt==`function`&&typeof e.getBigInt64==`function`&&typeof e.getBigUint64==`function`&&typeof e.setBigInt64==`function`&&typeof e.setBigUint64==`function`&&(globalThis.Deno||globalThis.Bun||typeof process!=`object`||{}.BUF_BIGINT_DISABLE!==`1`)){let t=BigInt(`-9223372036854775808`),n=BigInt(`9223372036854775807`),r=BigInt(`0`),i=BigInt(`18446744073709551615`);return{zero:BigInt(0),supported:!0,parse(e){let r=typeof e==`bigint`?e:BigInt(e);if(r>n||r<t)throw Error(`invalid int64: ${e}`);return r},uParse(e){let t=typeof e==`bigint`?e:BigInt(e);if(t>i||t<r)throw Error(`invalid uint64: ${e}`);return t},enc(t){return e.setBigInt64(0,this.parse(t),!0),{lo:e.getInt32(0,!0),hi:e.getInt32(4,!0)}},uEnc(t){return e.setBigInt64(0,this.uParse(t),!0),{lo:e.getInt32(0,!0),hi:e.getInt32(4,!0)}},dec(t,n){return e.setInt32(0,t,!0),e.setInt32(4,n,!0),e.getBigInt64(0,!0)},uDec(t,n){return e.setInt32(0,t,!0),e.setInt32(4,n,!0),e.getBigUint64(0,!0)}}}return{zero:`0`,supported:!1,parse(e){return typeof e!=`string`&&(e=e.toString()),h(e),e},uParse(e){return typeof e!=`string`&&(e=e.toString()),g(e),e},enc(e){return typeof e!=`string`&&(e=e.toString()),h(e),i(e)},uEnc(e){return typeof e!=`string`&&(e=e.toString()),g(e),i(e)},dec(e,t){return a(e,t)},uDec(e,t){return o(e,t)}}}function h(e){if(!/^-?[0-9]+$/.test(e))throw Error(`invalid int64: `+e)}function g(e){if(!/^[0-9]+$/.test(e))throw Error(`invalid uint64: `+e)}function _(e,n){switch(e){case t.STRING:return``;case t.BOOL:return!1;case t.DOUBLE:case t.FLOAT:return 0;case t.INT64:case t.UINT64:case t.SFIXED64:case t.FIXED64:case t.SINT64:return n?`0`:p.zero;case t.BYTES:return new Uint8Array;default:return 0}}function v(e,n){switch(e){case t.BOOL:return n===!1;case t.STRING:return n===``;case t.BYTES:return n instanceof Uint8Array&&!n.byteLength;case t.DOUBLE:case t.FLOAT:return Object.is(n,0);default:return n==0}}var y=2,b=Symbol.for(`reflect unsafe local`);function x(e,t){let n=e[t.localName].case;return n===void 0?n:t.fields.find(e=>e.localName===n)}function S(e,t){let n=t.localName;if(t.oneof)return e[t.oneof.localName].case===n;if(t.presence!=y)return e[n]!==void 0&&Object.prototype.hasOwnProperty.call(e,n);switch(t.fieldKind){case`list`:return e[n].length>0;case`map`:return Object.keys(e[n]).length>0;case`scalar`:return!v(t.scalar,e[n]);case`enum`:return e[n]!==t.enum.values[0].number}throw Error(`message field with implicit presence`)}function C(e,t){return Object.prototype.hasOwnProperty.call(e,t)&&e[t]!==void 0}function w(e,t){if(t.oneof){let n=e[t.oneof.localName];return n.case===t.localName?n.value:void 0}return e[t.localName]}function T(e,t,n){t.oneof?e[t.oneof.localName]={case:t.localName,value:n}:e[t.localName]=n}function E(e,t,n){t===`__proto__`?Object.defineProperty(e,"__proto__",{value:n,writable:!0,enumerable:!0,configurable:!0}):e[t]=n}function ee(e,t){return Object.prototype.hasOwnProperty.call(e,t)?e[t]:void 0}function D(e,t){let n=t.localName;if(t.oneof){let r=t.oneof.localName;e[r].case===n&&(e[r]={case:void 0})}else if(t.presence!=y)delete e[n];else switch(t.fieldKind){case`map`:e[n]={};break;case`list`:e[n]=[];break;case`enum`:e[n]=t.enum.values[0].number;break;case`scalar`:e[n]=_(t.scalar,t.longAsString)}}function O(e){return typeof e==`object`&&!!e&&!Array.isArray(e)}function k(e,t){if(O(e)&&b in e&&`add`in e&&`field`in e&&typeof e.field==`function`){if(t!==void 0){let n=t,r=e.field();return n.listKind==r.listKind&&n.scalar===r.scalar&&n.message?.typeName===r.message?.typeName&&n.enum?.typeName===r.enum?.typeName}return!0}return!1}function A(e,t){if(O(e)&&b in e&&`has`in e&&`field`in e&&typeof e.field==`function`){if(t!==void 0){let n=t,r=e.field();return n.mapKey===r.mapKey&&n.mapKind==r.mapKind&&n.scalar===r.scalar&&n.message?.typeName===r.message?.typeName&&n.enum?.typeName===r.enum?.typeName}return!0}return!1}function j(e,t){return O(e)&&b in e&&`desc`in e&&O(e.desc)&&e.desc.kind===`message`&&(t===void 0||e.desc.typeName==t.typeName)}function te(e){return ie(e.$typeName)}function M(e){let t=e.fields[0];return ie(e.typeName)&&t!==void 0&&t.fieldKind==`scalar`&&t.name==`value`&&t.number==1}function ne(e){switch(e.typeName){case`google.protobuf.Any`:case`google.protobuf.Timestamp`:case`google.protobuf.Duration`:case`google.protobuf.FieldMask`:case`google.protobuf.Struct`:case`google.protobuf.Value`:case`google.protobuf.ListValue`:return!0;default:return M(e)}}var re=new Set([`google.protobuf.DoubleValue`,`google.protobuf.FloatValue`,`google.protobuf.Int64Value`,`google.protobuf.UInt64Value`,`google.protobuf.Int32Value`,`google.protobuf.UInt32Value`,`google.protobuf.BoolValue`,`google.protobuf.StringValue`,`google.protobuf.BytesValue`]);function ie(e){return re.has(e)}var ae=999,oe=998,se=2;function N(t,n){return e(n,t)?n:P(t)(n)}var ce=new WeakMap;function P(e){let t=ce.get(e);return t===void 0&&(t=pe(e),ce.set(e,t)),t}var le=0,ue=1,de=2,fe=3;function pe(e){let t=e.typeName,{properties:n,prototype:r}=me(e);return e=>{let i;r===void 0?i={$typeName:t}:(i=Object.create(r),i.$typeName=t);for(let t=0;t<n.length;t++){let r=n[t],a=r.name,o=e?.[a];switch(r.kind){case le:o==null?r.constant!==void 0&&(i[a]=r.constant):i[a]=r.convert===void 0?o:r.convert(o);break;case ue:i[a]=r.convert!==void 0&&Array.isArray(o)?o.map(r.convert):o??[];break;case de:if(r.convert===void 0||!O(o))i[a]=o??{};else{let e={},t=Object.keys(o);for(let n=0;n<t.length;n++)E(e,t[n],r.convert(o[t[n]]));i[a]=e}break;case fe:{let e=o;if(e?.case!=null){let t=r.convert.get(e.case);if(t!==void 0){i[a]={case:e.case,value:t(e.value)};break}}i[a]={case:void 0};break}}}return i}}function me(e){let n=[],r={},i=ve(e);for(let a of e.members){let e=a.localName;if(a.kind==`oneof`)n.push({name:e,kind:fe,constant:void 0,convert:he(a)});else switch(a.fieldKind){case`message`:n.push({name:e,kind:le,constant:void 0,convert:ge(a)});break;case`list`:n.push({name:e,kind:ue,constant:void 0,convert:a.listKind==`message`?ge(a)??(e=>e):a.scalar==t.BYTES?_e:void 0});break;case`map`:n.push({name:e,kind:de,constant:void 0,convert:a.mapKind==`message`?ge(a)??(e=>e):a.scalar==t.BYTES?_e:void 0});break;default:{let o=ye(a);n.push({name:e,kind:le,constant:a.presence==se?o:void 0,convert:a.fieldKind==`scalar`&&a.scalar==t.BYTES?_e:void 0}),i&&(r[e]=o);break}}}return{properties:n,prototype:i?r:void 0}}function he(e){let n=new Map;for(let r of e.fields){let e;r.fieldKind==`message`?e=ge(r):r.fieldKind==`scalar`&&r.scalar==t.BYTES&&(e=_e),n.set(r.localName,e??(e=>e))}return n}function ge(n){if(n.fieldKind==`message`&&!n.oneof&&M(n.message))return n.message.fields[0].scalar==t.BYTES?_e:void 0;if(n.message.typeName==`google.protobuf.Struct`&&n.parent.typeName!==`google.protobuf.Value`)return;let r=n.message,i;return t=>!O(t)||e(t,r)?t:(i??=P(r),i(t))}function _e(e){return Array.isArray(e)?new Uint8Array(e):e}function ve(e){switch(e.file.edition){case ae:return!1;case oe:return!0;default:return e.fields.some(e=>e.presence!=se&&e.fieldKind!=`message`&&!e.oneof)}}function ye(e){let t=e.getDefaultValue();return t===void 0?e.fieldKind==`scalar`?_(e.scalar,e.longAsString):e.enum.values[0].number:e.fieldKind==`scalar`&&e.longAsString?t.toString():t}var be=[`FieldValueInvalidError`,`FieldListRangeError`,`ForeignFieldError`],F=class extends Error{constructor(e,t,n=`FieldValueInvalidError`){super(t),this.name=n,this.field=()=>e}};function xe(e){return e instanceof Error&&be.includes(e.name)&&`field`in e&&typeof e.field==`function`}var Se;function Ce(e){Se=Object.assign(Object.assign({},e),{encodeUtf8Into:e.encodeUtf8Into??Te(e.encodeUtf8.bind(e))})}function we(){if(!Se){let e=globalThis;if(!e.TextEncoder||!e.TextDecoder)throw Error(`encoding API missing: install TextEncoder and TextDecoder on globalThis`);let t=new e.TextEncoder,n=new e.TextDecoder(`utf-8`,{ignoreBOM:!0}),r,i={encodeUtf8(e){return t.encode(e)},decodeUtf8(t,i){return i?(r||=new e.TextDecoder(`utf-8`,{fatal:!0,ignoreBOM:!0}),r.decode(t)):n.decode(t)},checkUtf8(e){try{return encodeURIComponent(e),!0}catch{return!1}}};t.encodeInto&&(i.encodeUtf8Into=t.encodeInto.bind(t));let a=String.prototype.isWellFormed;a&&(i.checkUtf8=e=>a.call(e)),Ce(i)}return Se}function Te(e){return(t,n)=>{let r=e(t);return n.set(r),{written:r.byteLength}}}var I;(function(e){e[e.Varint=0]=`Varint`,e[e.Bit64=1]=`Bit64`,e[e.LengthDelimited=2]=`LengthDelimited`,e[e.StartGroup=3]=`StartGroup`,e[e.EndGroup=4]=`EndGroup`,e[e.Bit32=5]=`Bit32`})(I||={});var Ee=class{constructor(e){this.stackPos=[],this.encodeUtf8Into=e?Te(e):we().encodeUtf8Into,this.buffer=ke,this.viewCache=Ae,this.pos=0}ensureCapacity(e){let t=this.pos+e;if(t>this.buffer.length){let e=this.buffer.length||De;for(;e<t;)e*=2;let n=new Uint8Array(e);this.pos>0&&n.set(this.buffer),this.buffer=n}}view(){let e=this.buffer,t=this.viewCache;if(t.byteLength===e.byteLength)return t;let n=new DataView(e.buffer);return this.viewCache=n,n}finish(){let e=this.buffer.slice(0,this.pos);return this.pos=0,this.stackPos=[],e}fork(){return this.stackPos.push(this.pos),this.ensureCapacity(Oe),this.buffer[this.pos++]=0,this}join(){let e=this.stackPos.pop();if(e===void 0)throw Error(`invalid state, fork stack empty`);let t=this.pos-e-Oe,n=Me(t);return n>Oe&&(this.ensureCapacity(n-Oe),this.buffer.copyWithin(e+n,e+Oe,this.pos)),this.pos=e,this.uint32(t),this.pos+=t,this}tag(e,t){return this.uint32((e<<3|t)>>>0)}raw(e){return this.ensureCapacity(e.length),this.buffer.set(e,this.pos),this.pos+=e.length,this}uint32(e){if(Fe(e),this.ensureCapacity(5),e<128)return this.buffer[this.pos++]=e,this;for(;e>127;)this.buffer[this.pos++]=e&127|128,e>>>=7;return this.buffer[this.pos++]=e,this}int32(e){if(Pe(e),e>=0)return this.uint32(e);this.ensureCapacity(10);for(let t=0;t<9;t++)this.buffer[this.pos++]=e&127|128,e>>=7;return this.buffer[this.pos++]=1,this}bool(e){return this.ensureCapacity(1),this.buffer[this.pos++]=+!!e,this}bytes(e){return this.uint32(e.byteLength),this.raw(e)}string(e){typeof e!=`string`&&(e=String(e));let t=e.length;if(t<=je){this.ensureCapacity(t+1);let n=this.buffer,r=this.pos;n[r++]=t;let i=0;for(;i<t;i++){let t=e.charCodeAt(i);if(t>127)break;n[r++]=t}if(i==t)return this.pos=r,this}this.ensureCapacity(t*3+5);let n=Me(t),r=this.buffer,i=this.pos,{written:a}=this.encodeUtf8Into(e,r.subarray(i+n)),o=Me(a);return o!=n&&r.copyWithin(i+o,i+n,i+n+a),this.uint32(a),this.pos+=a,this}float(e){return Ie(e),this.ensureCapacity(4),this.view().setFloat32(this.pos,e,!0),this.pos+=4,this}double(e){return this.ensureCapacity(8),this.view().setFloat64(this.pos,e,!0),this.pos+=8,this}fixed32(e){return Fe(e),this.ensureCapacity(4),this.view().setUint32(this.pos,e,!0),this.pos+=4,this}sfixed32(e){return Pe(e),this.ensureCapacity(4),this.view().setInt32(this.pos,e,!0),this.pos+=4,this}sint32(e){return Pe(e),this.uint32((e<<1^e>>31)>>>0)}sfixed64(e){let t=p.enc(e);this.ensureCapacity(8);let n=this.view();return n.setInt32(this.pos,t.lo,!0),n.setInt32(this.pos+4,t.hi,!0),this.pos+=8,this}fixed64(e){let t=p.uEnc(e);this.ensureCapacity(8);let n=this.view();return n.setInt32(this.pos,t.lo,!0),n.setInt32(this.pos+4,t.hi,!0),this.pos+=8,this}int64(e){let t=p.enc(e);return this.writeVarint64(t.lo,t.hi)}sint64(e){let t=p.enc(e),n=t.hi>>31,r=t.lo<<1^n,i=(t.hi<<1|t.lo>>>31)^n;return this.writeVarint64(r,i)}uint64(e){let t=p.uEnc(e);return this.writeVarint64(t.lo,t.hi)}writeVarint64(e,t){this.ensureCapacity(10);let n=this.buffer,r=this.pos;for(let i=0;i<28;i+=7){let a=e>>>i,o=!(!(a>>>7)&&t==0);if(n[r++]=(o?a|128:a)&255,!o)return this.pos=r,this}let i=e>>>28&15|(t&7)<<4,a=!!(t>>3);if(n[r++]=(a?i|128:i)&255,!a)return this.pos=r,this;for(let e=3;e<31;e+=7){let i=t>>>e,a=!!(i>>>7);if(n[r++]=(a?i|128:i)&255,!a)return this.pos=r,this}return n[r++]=t>>>31&1,this.pos=r,this}},De=128,Oe=1,ke=new Uint8Array,Ae=new DataView(ke.buffer),je=32;function Me(e){return e<128?1:e<16384?2:e<2097152?3:e<268435456?4:5}var Ne=class{constructor(e,t=we().decodeUtf8){this.decodeUtf8=t,this.varint64Lo=0,this.varint64Hi=0,this.varint64=n,this.uint32=f,this.buf=e,this.len=e.length,this.pos=0,this.view=new DataView(e.buffer,e.byteOffset,e.byteLength)}tag(){let e=this.pos,t=this.uint32(),n=this.pos-e;if(n>5||n==5&&this.buf[this.pos-1]>15)throw Error(`illegal tag: varint overflows uint32`);let r=t>>>3,i=t&7;if(r<=0||i>5)throw Error(`illegal tag: field no `+r+` wire type `+i);return[r,i]}skip(e,t,n=100){let r=this.pos;switch(e){case I.Varint:for(;this.buf[this.pos++]&128;);break;case I.Bit64:this.pos+=4;case I.Bit32:this.pos+=4;break;case I.LengthDelimited:let r=this.uint32();this.pos+=r;break;case I.StartGroup:if(n<=0)throw Error(`maximum recursion depth reached`);for(;;){let[e,r]=this.tag();if(r===I.EndGroup){if(t!==void 0&&e!==t)throw Error(`invalid end group tag`);break}this.skip(r,e,n-1)}break;default:throw Error(`cant skip wire type `+e)}return this.assertBounds(),this.buf.subarray(r,this.pos)}assertBounds(){if(this.pos>this.len)throw RangeError(`premature EOF`)}int32(){return this.uint32()|0}sint32(){let e=this.uint32();return e>>>1^-(e&1)}int64(){return this.varint64(),p.dec(this.varint64Lo,this.varint64Hi)}uint64(){return this.varint64(),p.uDec(this.varint64Lo,this.varint64Hi)}sint64(){this.varint64();let e=this.varint64Lo,t=this.varint64Hi,n=-(e&1);return e=(e>>>1|(t&1)<<31)^n,t=t>>>1^n,p.dec(e,t)}bool(){let e=this.buf[this.pos];return e<128?(this.pos++,e!==0):(this.varint64(),this.varint64Lo!==0||this.varint64Hi!==0)}fixed32(){return this.view.getUint32((this.pos+=4)-4,!0)}sfixed32(){return this.view.getInt32((this.pos+=4)-4,!0)}fixed64(){return p.uDec(this.sfixed32(),this.sfixed32())}sfixed64(){return p.dec(this.sfixed32(),this.sfixed32())}float(){return this.view.getFloat32((this.pos+=4)-4,!0)}double(){return this.view.getFloat64((this.pos+=8)-8,!0)}bytes(){let e=this.uint32(),t=this.pos;return this.pos+=e,this.assertBounds(),this.buf.subarray(t,t+e)}string(e){let t=this.uint32(),n=this.pos;this.pos+=t,this.assertBounds();let r=this.buf;if(t<=je){let i=Array(t);for(let a=0;a<t;a++){let t=r[n+a];if(t>127)return this.decodeUtf8(r.subarray(n,this.pos),e);i[a]=t}return String.fromCharCode.apply(String,i)}return this.decodeUtf8(r.subarray(n,this.pos),e)}};function Pe(e){if(typeof e==`string`)e=Number(e);else if(typeof e!=`number`)throw Error(`invalid int32: `+typeof e);if(!Number.isInteger(e)||e>0x7fffffff||e<-0x80000000)throw Error(`invalid int32: `+e)}function Fe(e){if(typeof e==`string`)e=Number(e);else if(typeof e!=`number`)throw Error(`invalid uint32: `+typeof e);if(!Number.isInteger(e)||e>0xffffffff||e<0)throw Error(`invalid uint32: `+e)}function Ie(e){if(typeof e==`string`){let t=e;if(e=Number(e),Number.isNaN(e)&&t!==`NaN`)throw Error(`invalid float32: `+t)}else if(typeof e!=`number`)throw Error(`invalid float32: `+typeof e);if(!Number.isFinite(Math.fround(e))&&Number.isFinite(e))throw Error(`invalid float32: `+e)}function Le(e,t){let n=e.fieldKind==`list`?k(t,e):e.fieldKind==`map`?A(t,e):Be(e,t);if(n===!0)return;let r;switch(e.fieldKind){case`list`:r=`expected ${We(e)}, got ${L(t)}`;break;case`map`:r=`expected ${Ge(e)}, got ${L(t)}`;break;default:r=He(e,t,n)}return new F(e,r)}function Re(e,t,n){let r=Be(e,n);if(r!==!0)return new F(e,`list item #${t+1}: ${He(e,n,r)}`)}function ze(e,t,n){let r=Ve(e.mapKey)(t);if(r!==!0)return new F(e,`invalid map key: ${He({scalar:e.mapKey},t,r)}`);let i=Be(e,n);if(i!==!0)return new F(e,`map entry ${L(t)}: ${He(e,n,i)}`)}function Be(e,n){return e.scalar===void 0?e.enum===void 0?j(n,e.message):e.enum.open?Ve(t.INT32)(n):e.enum.values.some(e=>e.number===n):Ve(e.scalar)(n)}function Ve(e){switch(e){case t.DOUBLE:return e=>typeof e==`number`;case t.FLOAT:return e=>typeof e==`number`?!Number.isFinite(Math.fround(e))&&Number.isFinite(e)?`${e.toFixed()} out of range`:!0:!1;case t.INT32:case t.SFIXED32:case t.SINT32:return e=>typeof e!=`number`||!Number.isInteger(e)?!1:e>0x7fffffff||e<-0x80000000?`${e.toFixed()} out of range`:!0;case t.FIXED32:case t.UINT32:return e=>typeof e!=`number`||!Number.isInteger(e)?!1:e>0xffffffff||e<0?`${e.toFixed()} out of range`:!0;case t.BOOL:return e=>typeof e==`boolean`;case t.STRING:return e=>typeof e==`string`?we().checkUtf8(e)||`invalid UTF8`:!1;case t.BYTES:return e=>e instanceof Uint8Array;case t.INT64:case t.SFIXED64:case t.SINT64:return e=>{if(typeof e==`bigint`||typeof e==`number`||typeof e==`string`&&e.length>0)try{return p.parse(e),!0}catch{return`${e} out of range`}return!1};case t.FIXED64:case t.UINT64:return e=>{if(typeof e==`bigint`||typeof e==`number`||typeof e==`string`&&e.length>0)try{return p.uParse(e),!0}catch{return`${e} out of range`}return!1}}}function He(e,t,n){return n=typeof n==`string`?`: ${n}`:`, got ${L(t)}`,e.scalar===void 0?e.enum===void 0?`expected ${Ue(e.message)}`+n:`expected ${e.enum.toString()}`+n:`expected ${Ke(e.scalar)}`+n}function L(t){switch(typeof t){case`object`:return t===null?`null`:t instanceof Uint8Array?`Uint8Array(${t.length})`:Array.isArray(t)?`Array(${t.length})`:k(t)?We(t.field()):A(t)?Ge(t.field()):j(t)?Ue(t.desc):e(t)?`message ${t.$typeName}`:`object`;case`string`:return t.length>30?`string`:`"${t.split(`"`).join(`\\"`)}"`;case`boolean`:case`number`:return String(t);case`bigint`:return String(t)+`n`;default:return typeof t}}function Ue(e){return`ReflectMessage (${e.typeName})`}function We(e){switch(e.listKind){case`message`:return`ReflectList (${e.message.toString()})`;case`enum`:return`ReflectList (${e.enum.toString()})`;case`scalar`:return`ReflectList (${t[e.scalar]})`}}function Ge(e){switch(e.mapKind){case`message`:return`ReflectMap (${t[e.mapKey]}, ${e.message.toString()})`;case`enum`:return`ReflectMap (${t[e.mapKey]}, ${e.enum.toString()})`;case`scalar`:return`ReflectMap (${t[e.mapKey]}, ${t[e.scalar]})`}}function Ke(e){switch(e){case t.STRING:return`string`;case t.BOOL:return`boolean`;case t.INT64:case t.SINT64:case t.SFIXED64:return`bigint (int64)`;case t.UINT64:case t.FIXED64:return`bigint (uint64)`;case t.BYTES:return`Uint8Array`;case t.DOUBLE:return`number (float64)`;case t.FLOAT:return`number (float32)`;case t.FIXED32:case t.UINT32:return`number (uint32)`;case t.INT32:case t.SFIXED32:case t.SINT32:return`number (int32)`}}var qe=0;function Je(e){if(Ye(e))return{toMessage:e=>Xe(e),toLocal:e=>Ze(e)};if(e.fieldKind==`message`&&!e.oneof&&M(e.message)){let t=e.message,n=t.fields[0].localName;return{toMessage:e=>{let r=N(t);return e!==void 0&&(r[n]=e),r},toLocal:e=>e[n]}}let t=e.message;return{toMessage:e=>e===void 0?N(t):e,toLocal:e=>e}}function Ye(e){return e.message.typeName==`google.protobuf.Struct`&&e.parent.typeName!=`google.protobuf.Value`}function Xe(e){let t={$typeName:`google.protobuf.Struct`,fields:{}};if(O(e))for(let n of Object.keys(e))E(t.fields,n,$e(e[n]));return t}function Ze(e){let t={};for(let n of Object.keys(e.fields))E(t,n,Qe(e.fields[n]));return t}function Qe(e){switch(e.kind.case){case`structValue`:return Ze(e.kind.value);case`listValue`:return e.kind.value.values.map(Qe);case`nullValue`:case void 0:return null;default:return e.kind.value}}function $e(e){let t={$typeName:`google.protobuf.Value`,kind:{case:void 0}};switch(typeof e){case`number`:t.kind={case:`numberValue`,value:e};break;case`string`:t.kind={case:`stringValue`,value:e};break;case`boolean`:t.kind={case:`boolValue`,value:e};break;case`object`:if(e===null)t.kind={case:`nullValue`,value:qe};else if(Array.isArray(e)){let n={$typeName:`google.protobuf.ListValue`,values:[]};if(Array.isArray(e))for(let t of e)n.values.push($e(t));t.kind={case:`listValue`,value:n}}else t.kind={case:`structValue`,value:Xe(e)}}return t}function et(e,t,n=!0){return new nt(e,t,n)}var tt=new WeakMap,nt=class{get sortedFields(){let e=tt.get(this.desc);if(e)return e;let t=this.desc.fields.concat().sort((e,t)=>e.number-t.number);return tt.set(this.desc,t),t}constructor(e,t,n=!0){this.lists=new Map,this.maps=new Map,this.check=n,this.desc=e,this.message=this[b]=t??N(e),this.fields=e.fields,this.oneofs=e.oneofs,this.members=e.members}findNumber(e){return this._fieldsByNumber||=new Map(this.desc.fields.map(e=>[e.number,e])),this._fieldsByNumber.get(e)}oneofCase(e){return rt(this.message,e),x(this.message,e)}isSet(e){return rt(this.message,e),S(this.message,e)}clear(e){rt(this.message,e),D(this.message,e)}get(e){rt(this.message,e);let t=w(this.message,e);switch(e.fieldKind){case`list`:let n=this.lists.get(e);return n&&n[b]===t||this.lists.set(e,n=new it(e,t,this.check)),n;case`map`:let r=this.maps.get(e);return r&&r[b]===t||this.maps.set(e,r=new at(e,t,this.check)),r;case`message`:return st(e,t,this.check);case`scalar`:return t===void 0?_(e.scalar,!1):mt(e,t);case`enum`:return t??e.enum.values[0].number}}set(e,t){if(rt(this.message,e),this.check){let n=Le(e,t);if(n)throw n}let n;n=e.fieldKind==`message`?ot(e,t):A(t)||k(t)?t[b]:ht(e,t),T(this.message,e,n)}getUnknown(){return this.message.$unknown}setUnknown(e){this.message.$unknown=e}};function rt(e,t){if(t.parent.typeName!==e.$typeName)throw new F(t,`cannot use ${t.toString()} with message ${e.$typeName}`,`ForeignFieldError`)}var it=class{field(){return this._field}get size(){return this._arr.length}constructor(e,t,n){this._field=e,this._arr=this[b]=t,this.check=n}get(e){let t=this._arr[e];return t===void 0?void 0:lt(this._field,t,this.check)}set(e,t){if(e<0||e>=this._arr.length)throw new F(this._field,`list item #${e+1}: out of range`);if(this.check){let n=Re(this._field,e,t);if(n)throw n}this._arr[e]=ct(this._field,t)}add(e){if(this.check){let t=Re(this._field,this._arr.length,e);if(t)throw t}this._arr.push(ct(this._field,e))}clear(){this._arr.splice(0,this._arr.length)}[Symbol.iterator](){return this.values()}keys(){return this._arr.keys()}*values(){for(let e of this._arr)yield lt(this._field,e,this.check)}*entries(){for(let e=0;e<this._arr.length;e++)yield[e,lt(this._field,this._arr[e],this.check)]}},at=class{constructor(e,t,n=!0){this.obj=this[b]=t??{},this.check=n,this._field=e}field(){return this._field}set(e,t){if(this.check){let n=ze(this._field,e,t);if(n)throw n}return E(this.obj,ft(e),ut(this._field,t)),this}delete(e){let t=ft(e),n=Object.prototype.hasOwnProperty.call(this.obj,t);return n&&delete this.obj[t],n}clear(){for(let e of Object.keys(this.obj))delete this.obj[e]}get(e){let t=ee(this.obj,ft(e));return t!==void 0&&(t=dt(this._field,t,this.check)),t}has(e){return Object.prototype.hasOwnProperty.call(this.obj,ft(e))}*keys(){for(let e of Object.keys(this.obj))yield pt(e,this._field.mapKey)}*entries(){for(let e of Object.entries(this.obj))yield[pt(e[0],this._field.mapKey),dt(this._field,e[1],this.check)]}[Symbol.iterator](){return this.entries()}get size(){return Object.keys(this.obj).length}*values(){for(let e of Object.values(this.obj))yield dt(this._field,e,this.check)}forEach(e,t){for(let n of this.entries())e.call(t,n[1],n[0],this)}};function ot(e,t){return j(t)?te(t.message)&&!e.oneof&&e.fieldKind==`message`?t.message.value:t.desc.typeName==`google.protobuf.Struct`&&e.parent.typeName!=`google.protobuf.Value`?Ze(t.message):t.message:t}function st(e,t,n){return t!==void 0&&(M(e.message)&&!e.oneof&&e.fieldKind==`message`?t={$typeName:e.message.typeName,value:mt(e.message.fields[0],t)}:e.message.typeName==`google.protobuf.Struct`&&e.parent.typeName!=`google.protobuf.Value`&&O(t)&&(t=Xe(t))),new nt(e.message,t,n)}function ct(e,t){return e.listKind==`message`?ot(e,t):ht(e,t)}function lt(e,t,n){return e.listKind==`message`?st(e,t,n):mt(e,t)}function ut(e,t){return e.mapKind==`message`?ot(e,t):ht(e,t)}function dt(e,t,n){return e.mapKind==`message`?st(e,t,n):t}function ft(e){return typeof e==`string`||typeof e==`number`?e:String(e)}function pt(e,n){switch(n){case t.STRING:return e;case t.INT32:case t.FIXED32:case t.UINT32:case t.SFIXED32:case t.SINT32:{let t=Number.parseInt(e);if(Number.isFinite(t))return t;break}case t.BOOL:switch(e){case`true`:return!0;case`false`:return!1}break;case t.UINT64:case t.FIXED64:try{return p.uParse(e)}catch{}break;default:try{return p.parse(e)}catch{}}return e}function mt(e,n){switch(e.scalar){case t.INT64:case t.SFIXED64:case t.SINT64:`longAsString`in e&&e.longAsString&&typeof n==`string`&&(n=p.parse(n));break;case t.FIXED64:case t.UINT64:`longAsString`in e&&e.longAsString&&typeof n==`string`&&(n=p.uParse(n))}return n}function ht(e,n){switch(e.scalar){case t.INT64:case t.SFIXED64:case t.SINT64:`longAsString`in e&&e.longAsString?n=String(n):(typeof n==`string`||typeof n==`number`)&&(n=p.parse(n));break;case t.FIXED64:case t.UINT64:`longAsString`in e&&e.longAsString?n=String(n):(typeof n==`string`||typeof n==`number`)&&(n=p.uParse(n))}return n}var gt=Uint8Array.prototype.setFromBase64;function _t(e){let t=e.length,n=t-(t+3>>2);!(t&3)&&e[t-1]==`=`&&(n-=e[t-2]==`=`?2:1);let r=new Uint8Array(n),i=-1;if(gt)try{let n=gt.call(r,e);n.read==t&&(i=n.written)}catch{}return i<0&&(i=vt(r,e)),i==n?r:r.subarray(0,i)}function vt(e,t){let n=Et(),r=0,i=0,a,o=0;for(let s=0;s<t.length;s++){if(a=n[t.charCodeAt(s)],a===void 0)switch(t[s]){case`=`:i=0;case`
`:case`\r`:case`	`:case` `:continue;default:throw Error(`invalid base64 string`)}switch(i){case 0:o=a,i=1;break;case 1:e[r++]=o<<2|(a&48)>>4,o=a,i=2;break;case 2:e[r++]=(o&15)<<4|(a&60)>>2,o=a,i=3;break;case 3:e[r++]=(o&3)<<6|a,i=0}}if(i==1)throw Error(`invalid base64 string`);return r}var yt=Uint8Array.prototype.toBase64,bt={std:{alphabet:`base64`,omitPadding:!1},std_raw:{alphabet:`base64`,omitPadding:!0},url:{alphabet:`base64url`,omitPadding:!0}};function xt(e,t=`std`){if(yt)return yt.call(e,bt[t]);let n=Tt(t),r=t==`std`,i=``,a=0,o,s=0;for(let t=0;t<e.length;t++)switch(o=e[t],a){case 0:i+=n[o>>2],s=(o&3)<<4,a=1;break;case 1:i+=n[s|o>>4],s=(o&15)<<2,a=2;break;case 2:i+=n[s|o>>6],i+=n[o&63],a=0}return a&&(i+=n[s],r&&(i+=`=`,a==1&&(i+=`=`))),i}var St,Ct,wt;function Tt(e){return St||(St=`ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/`.split(``),Ct=St.slice(0,-2).concat(`-`,`_`)),e==`url`?Ct:St}function Et(){if(!wt){wt=[];let e=Tt(`std`);for(let t=0;t<e.length;t++)wt[e[t].charCodeAt(0)]=t;wt[45]=e.indexOf(`+`),wt[95]=e.indexOf(`/`)}return wt}function Dt(e){let t=!1,n=[];for(let r=0;r<e.length;r++){let i=e.charAt(r);switch(i){case`_`:t=!0;break;case`0`:case`1`:case`2`:case`3`:case`4`:case`5`:case`6`:case`7`:case`8`:case`9`:n.push(i),t=!1;break;default:t&&(t=!1,i=i.toUpperCase()),n.push(i)}}return n.join(``)}function Ot(e){return e.replace(/[A-Z]/g,e=>`_`+e.toLowerCase())}var kt=new Set([`constructor`,`toString`,`toJSON`,`valueOf`]);function At(e){return kt.has(e)?e+`$`:e}function jt(e){for(let t of e.field)C(t,`jsonName`)||(t.jsonName=Dt(t.name));e.nestedType.forEach(jt)}function Mt(e,t){let n=e.values.find(e=>e.name===t);if(!n)throw Error(`cannot parse ${e} default value: ${t}`);return n.number}function Nt(e,n){switch(e){case t.STRING:return n;case t.BYTES:{let r=Pt(n);if(r===!1)throw Error(`cannot parse ${t[e]} default value: ${n}`);return r}case t.INT64:case t.SFIXED64:case t.SINT64:return p.parse(n);case t.UINT64:case t.FIXED64:return p.uParse(n);case t.DOUBLE:case t.FLOAT:switch(n){case`inf`:return 1/0;case`-inf`:return-1/0;case`nan`:return NaN;default:return parseFloat(n)}case t.BOOL:return n===`true`;case t.INT32:case t.UINT32:case t.SINT32:case t.FIXED32:case t.SFIXED32:return parseInt(n,10)}}function Pt(e){let t=[],n={tail:e,c:``,next(){return this.tail.length!=0&&(this.c=this.tail[0],this.tail=this.tail.substring(1),!0)},take(e){if(this.tail.length>=e){let t=this.tail.substring(0,e);return this.tail=this.tail.substring(e),t}return!1}};for(;n.next();)if(n.c===`\\`){if(n.next())switch(n.c){case`\\`:t.push(n.c.charCodeAt(0));break;case`b`:t.push(8);break;case`f`:t.push(12);break;case`n`:t.push(10);break;case`r`:t.push(13);break;case`t`:t.push(9);break;case`v`:t.push(11);break;case`0`:case`1`:case`2`:case`3`:case`4`:case`5`:case`6`:case`7`:{let e=n.c,r=n.take(2);if(r===!1)return!1;let i=parseInt(e+r,8);if(Number.isNaN(i))return!1;t.push(i);break}case`x`:{let e=n.c,r=n.take(2);if(r===!1)return!1;let i=parseInt(e+r,16);if(Number.isNaN(i))return!1;t.push(i);break}case`u`:{let e=n.c,r=n.take(4);if(r===!1)return!1;let i=parseInt(e+r,16);if(Number.isNaN(i))return!1;let a=new Uint8Array(4);new DataView(a.buffer).setInt32(0,i,!0),t.push(a[0],a[1],a[2],a[3]);break}case`U`:{let e=n.c,r=n.take(8);if(r===!1)return!1;let i=p.uEnc(e+r),a=new Uint8Array(8),o=new DataView(a.buffer);o.setInt32(0,i.lo,!0),o.setInt32(4,i.hi,!0),t.push(a[0],a[1],a[2],a[3],a[4],a[5],a[6],a[7]);break}}}else t.push(n.c.charCodeAt(0));return new Uint8Array(t)}function*Ft(e){switch(e.kind){case`file`:for(let t of e.messages)yield t,yield*Ft(t);yield*e.enums,yield*e.services,yield*e.extensions;break;case`message`:for(let t of e.nestedMessages)yield t,yield*Ft(t);yield*e.nestedEnums,yield*e.nestedExtensions}}function It(e,t){return Lt([e,t])}function Lt(e,t){let n=Rt();if(!e.length)return n;if(`$typeName`in e[0]&&e[0].$typeName==`google.protobuf.FileDescriptorSet`){for(let r of e[0].file)t?.(r),sn(r,n);return n}if(`$typeName`in e[0]){let r=e[0],i=e[1],a=new Set;function o(e){let t=[];for(let r of e.dependency){if(n.getFile(r)!=null||a.has(r))continue;let o=i(r);if(!o)throw Error(`Unable to resolve ${r}, imported by ${e.name}`);`kind`in o?n.addFile(o,!1,!0):(a.add(o.name),t.push(o))}return t.concat(...t.map(o))}for(let e of[r,...o(r)].reverse())t?.(e),sn(e,n)}else for(let t of e)for(let e of t.files)n.addFile(e);return n}function Rt(){let e=new Map,t=new Map,n=new Map;return{kind:`registry`,types:e,extendees:t,[Symbol.iterator](){return e.values()},get files(){return n.values()},addFile(e,t,r){if(n.set(e.proto.name,e),!t)for(let t of Ft(e))this.add(t);if(r)for(let n of e.dependencies)this.addFile(n,t,r)},add(n){if(n.kind==`extension`){let e=t.get(n.extendee.typeName);e||t.set(n.extendee.typeName,e=new Map),e.set(n.number,n)}e.set(n.typeName,n)},get(t){return e.get(t)},getFile(e){return n.get(e)},getMessage(t){let n=e.get(t);return n?.kind==`message`?n:void 0},getEnum(t){let n=e.get(t);return n?.kind==`enum`?n:void 0},getExtension(t){let n=e.get(t);return n?.kind==`extension`?n:void 0},getExtensionFor(e,n){return t.get(e.typeName)?.get(n)},getService(t){let n=e.get(t);return n?.kind==`service`?n:void 0}}}var zt=998,Bt=999,Vt=9999,Ht=9,Ut=10,Wt=11,Gt=12,Kt=14,qt=3,Jt=2,Yt=1,Xt=0,Zt=1,Qt=2,$t=3,en=1,tn=2,nn=1,rn=2,an=1002,on={998:{fieldPresence:1,enumType:2,repeatedFieldEncoding:2,utf8Validation:3,messageEncoding:1,jsonFormat:2,enforceNamingStyle:2,defaultSymbolVisibility:1,enforceProtoLimits:1},999:{fieldPresence:2,enumType:1,repeatedFieldEncoding:1,utf8Validation:2,messageEncoding:1,jsonFormat:1,enforceNamingStyle:2,defaultSymbolVisibility:1,enforceProtoLimits:1},1e3:{fieldPresence:1,enumType:1,repeatedFieldEncoding:1,utf8Validation:2,messageEncoding:1,jsonFormat:1,enforceNamingStyle:2,defaultSymbolVisibility:1,enforceProtoLimits:1},1001:{fieldPresence:1,enumType:1,repeatedFieldEncoding:1,utf8Validation:2,messageEncoding:1,jsonFormat:1,enforceNamingStyle:1,defaultSymbolVisibility:2,enforceProtoLimits:1},1002:{fieldPresence:1,enumType:1,repeatedFieldEncoding:1,utf8Validation:2,messageEncoding:1,jsonFormat:1,enforceNamingStyle:3,defaultSymbolVisibility:4,enforceProtoLimits:2}};function sn(e,t){let n={kind:`file`,proto:e,deprecated:e.options?.deprecated??!1,edition:gn(e),name:e.name.replace(/\.proto$/,``),dependencies:_n(e,t),enums:[],messages:[],extensions:[],services:[],toString(){return`file ${e.name}`}},r=new Map,i={get(e){return r.get(e)},add(e){jn(e.proto.options?.mapEntry===!0),r.set(e.typeName,e)}};for(let r of e.enumType)un(r,n,void 0,t);for(let r of e.messageType)dn(r,n,void 0,t,i);for(let r of e.service)fn(r,n,t);cn(n,t);for(let e of r.values())ln(e,t,i);for(let e of n.messages)ln(e,t,i),cn(e,t);t.addFile(n,!0)}function cn(e,t){switch(e.kind){case`file`:for(let n of e.proto.extension){let r=hn(n,e,t);e.extensions.push(r),t.add(r)}break;case`message`:for(let n of e.proto.extension){let r=hn(n,e,t);e.nestedExtensions.push(r),t.add(r)}for(let n of e.nestedMessages)cn(n,t)}}function ln(e,t,n){let r=e.proto.oneofDecl.map(t=>mn(t,e)),i=new Set;for(let a of e.proto.field){let o=Cn(a,r),s=hn(a,e,t,o,n);e.fields.push(s),e.field[s.localName]=s,o===void 0?e.members.push(s):(o.fields.push(s),i.has(o)||(i.add(o),e.members.push(o)))}for(let t of r.filter(e=>i.has(e)))e.oneofs.push(t);for(let r of e.nestedMessages)ln(r,t,n)}function un(e,t,n,r){var i,a;let o=vn(e.name,e.value),s={kind:`enum`,proto:e,deprecated:e.options?.deprecated??!1,file:t,parent:n,open:!0,name:e.name,typeName:xn(e,n,t),value:{},values:[],sharedPrefix:o,toString(){return`enum ${this.typeName}`}};s.open=Dn(s),r.add(s);for(let t of e.value){let e=t.name,n={kind:`enum_value`,proto:t,deprecated:t.options?.deprecated??!1,parent:s,name:e,localName:At(o==null?e:e.substring(o.length)),number:t.number,jsonName:yn(t)??e,toString(){return`enum value ${s.typeName}.${e}`}};s.values.push(n),(i=s.value)[a=t.number]??(i[a]=n)}(n?.nestedEnums??t.enums).push(s)}function dn(e,t,n,r,i){let a={kind:`message`,proto:e,deprecated:e.options?.deprecated??!1,file:t,parent:n,name:e.name,typeName:xn(e,n,t),fields:[],field:{},oneofs:[],members:[],nestedEnums:[],nestedMessages:[],nestedExtensions:[],toString(){return`message ${this.typeName}`}};e.options?.mapEntry===!0?i.add(a):((n?.nestedMessages??t.messages).push(a),r.add(a));for(let n of e.enumType)un(n,t,a,r);for(let n of e.nestedType)dn(n,t,a,r,i)}function fn(e,t,n){let r={kind:`service`,proto:e,deprecated:e.options?.deprecated??!1,file:t,name:e.name,typeName:xn(e,void 0,t),methods:[],method:{},toString(){return`service ${this.typeName}`}};t.services.push(r),n.add(r);for(let t of e.method){let e=pn(t,r,n);r.methods.push(e),r.method[e.localName]=e}}function pn(e,t,n){let r;r=e.clientStreaming&&e.serverStreaming?`bidi_streaming`:e.clientStreaming?`client_streaming`:e.serverStreaming?`server_streaming`:`unary`;let i=n.getMessage(Sn(e.inputType)),a=n.getMessage(Sn(e.outputType));jn(i,`invalid MethodDescriptorProto: input_type ${e.inputType} not found`),jn(a,`invalid MethodDescriptorProto: output_type ${e.inputType} not found`);let o=e.name;return{kind:`rpc`,proto:e,deprecated:e.options?.deprecated??!1,parent:t,name:o,localName:At(o.length?At(o[0].toLowerCase()+o.substring(1)):o),methodKind:r,input:i,output:a,idempotency:e.options?.idempotencyLevel??Xt,toString(){return`rpc ${t.typeName}.${o}`}}}function mn(e,t){return{kind:`oneof`,proto:e,deprecated:!1,parent:t,fields:[],name:e.name,localName:At(Dt(e.name)),toString(){return`oneof ${t.typeName}.${this.name}`}}}function hn(e,t,n,r,i){let a=i===void 0,o={kind:`field`,proto:e,deprecated:e.options?.deprecated??!1,name:e.name,number:e.number,scalar:void 0,message:void 0,enum:void 0,presence:wn(e,r,a,t),utf8Validation:kn(e,t),listKind:void 0,mapKind:void 0,mapKey:void 0,delimitedEncoding:void 0,packed:void 0,longAsString:!1,getDefaultValue:void 0},s;if(a){let r=t.kind==`file`?t:t.file,i=t.kind==`file`?void 0:t,a=xn(e,i,r);o.kind=`extension`,o.file=r,o.parent=i,o.oneof=void 0,o.typeName=a,o.jsonName=`[${a}]`,s=()=>`extension ${a}`;let c=n.getMessage(Sn(e.extendee));jn(c,`invalid FieldDescriptorProto: extendee ${e.extendee} not found`),o.extendee=c}else{let n=t;jn(n.kind==`message`),o.parent=n,o.oneof=r,o.localName=r?Dt(e.name):At(Dt(e.name)),o.jsonName=e.jsonName,s=()=>`field ${n.typeName}.${e.name}`}Object.defineProperty(o,"toString",{value:s,writable:!0,enumerable:!0,configurable:!0});let c=e.label,l=e.type,u=e.options?.jstype;if(c===qt){let r=l==Wt?i?.get(Sn(e.typeName)):void 0;if(r){o.fieldKind=`map`;let{key:e,value:t}=En(r);return o.mapKey=e.scalar,o.mapKind=t.fieldKind,o.message=t.message,o.delimitedEncoding=!1,o.enum=t.enum,o.scalar=t.scalar,o}switch(o.fieldKind=`list`,l){case Wt:case Ut:o.listKind=`message`,o.message=n.getMessage(Sn(e.typeName)),jn(o.message),o.delimitedEncoding=On(e,t);break;case Kt:o.listKind=`enum`,o.enum=n.getEnum(Sn(e.typeName)),jn(o.enum);break;default:o.listKind=`scalar`,o.scalar=l,o.longAsString=u==Yt}return o.packed=Tn(e,t),o}switch(l){case Wt:case Ut:o.fieldKind=`message`,o.message=n.getMessage(Sn(e.typeName)),jn(o.message,`invalid FieldDescriptorProto: type_name ${e.typeName} not found`),o.delimitedEncoding=On(e,t),o.getDefaultValue=()=>void 0;break;case Kt:{let t=n.getEnum(Sn(e.typeName));jn(t!==void 0,`invalid FieldDescriptorProto: type_name ${e.typeName} not found`),o.fieldKind=`enum`,o.enum=n.getEnum(Sn(e.typeName)),o.getDefaultValue=()=>C(e,`defaultValue`)?Mt(t,e.defaultValue):void 0;break}default:o.fieldKind=`scalar`,o.scalar=l,o.longAsString=u==Yt,o.getDefaultValue=()=>C(e,`defaultValue`)?Nt(l,e.defaultValue):void 0}return o}function gn(e){switch(e.syntax){case``:case`proto2`:return zt;case`proto3`:return Bt;case`editions`:if(e.edition===Vt)return an;if(e.edition in on)return e.edition;throw Error(`${e.name}: unsupported edition`);default:throw Error(`${e.name}: unsupported syntax "${e.syntax}"`)}}function _n(e,t){return e.dependency.map(n=>{let r=t.getFile(n);if(!r)throw Error(`Cannot find ${n}, imported by ${e.name}`);return r})}function vn(e,t){let n=bn(e)+`_`;for(let e of t){if(!e.name.toLowerCase().startsWith(n))return;let t=e.name.substring(n.length);if(t.length==0||/^\d/.test(t))return}return n}function yn(e){let t;for(let n of e.options?.$unknown??[]){if(n.no!==998||n.wireType!==I.LengthDelimited)continue;let e=new Ne(new Ne(n.data).bytes());for(;e.pos<e.len;){let[n,r]=e.tag();n===1&&r===I.LengthDelimited?t=e.string():e.skip(r,n)}}return t}function bn(e){return(e.substring(0,1)+e.substring(1).replace(/[A-Z]/g,e=>`_`+e)).toLowerCase()}function xn(e,t,n){let r;return r=t?`${t.typeName}.${e.name}`:n.proto.package.length>0?`${n.proto.package}.${e.name}`:`${e.name}`,r}function Sn(e){return e.startsWith(`.`)?e.substring(1):e}function Cn(e,t){if(!C(e,`oneofIndex`)||e.proto3Optional)return;let n=t[e.oneofIndex];return jn(n,`invalid FieldDescriptorProto: oneof #${e.oneofIndex} for field #${e.number} not found`),n}function wn(e,t,n,r){if(e.label==Jt)return $t;if(e.label==qt)return Qt;if(t||e.proto3Optional||n)return Zt;let i=An(`fieldPresence`,{proto:e,parent:r});return i==Qt&&(e.type==Wt||e.type==Ut)?Zt:i}function Tn(e,t){if(e.label!=qt)return!1;switch(e.type){case Ht:case Gt:case Ut:case Wt:return!1}let n=e.options;return n&&C(n,`packed`)?n.packed:en==An(`repeatedFieldEncoding`,{proto:e,parent:t})}function En(e){let n=e.fields.find(e=>e.number===1),r=e.fields.find(e=>e.number===2);return jn(n&&n.fieldKind==`scalar`&&n.scalar!=t.BYTES&&n.scalar!=t.FLOAT&&n.scalar!=t.DOUBLE&&r&&r.fieldKind!=`list`&&r.fieldKind!=`map`),{key:n,value:r}}function Dn(e){return nn==An(`enumType`,{proto:e.proto,parent:e.parent??e.file})}function On(e,t){return e.type==Ut||tn==An(`messageEncoding`,{proto:e,parent:t})}function kn(e,t){return rn==An(`utf8Validation`,{proto:e,parent:t})}function An(e,t){let n=t.proto.options?.features;if(n){let t=n[e];if(t!=0)return t}if(`kind`in t){if(t.kind==`message`)return An(e,t.parent??t.file);let n=on[t.edition];if(!n)throw Error(`feature default for edition ${t.edition} not found`);return n[e]}return An(e,t.parent)}function jn(e,t){if(!e)throw Error(t)}function Mn(e){let t=Nn(e);return t.messageType.forEach(jt),It(t,()=>void 0).getFile(t.name)}function Nn(e){return Object.assign(Object.create({syntax:``,edition:0}),Object.assign(Object.assign({$typeName:`google.protobuf.FileDescriptorProto`,dependency:[],publicDependency:[],weakDependency:[],optionDependency:[],service:[],extension:[]},e),{messageType:e.messageType.map(Pn),enumType:e.enumType.map(Ln)}))}function Pn(e){return Object.assign(Object.create({visibility:0}),{$typeName:`google.protobuf.DescriptorProto`,name:e.name,field:e.field?.map(Fn)??[],extension:[],nestedType:e.nestedType?.map(Pn)??[],enumType:e.enumType?.map(Ln)??[],extensionRange:e.extensionRange?.map(e=>Object.assign({$typeName:`google.protobuf.DescriptorProto.ExtensionRange`},e))??[],oneofDecl:[],reservedRange:[],reservedName:[]})}function Fn(e){return Object.assign(Object.create({label:1,typeName:``,extendee:``,defaultValue:``,oneofIndex:0,jsonName:``,proto3Optional:!1}),Object.assign(Object.assign({$typeName:`google.protobuf.FieldDescriptorProto`},e),{options:e.options?In(e.options):void 0}))}function In(e){return Object.assign(Object.create({ctype:0,packed:!1,jstype:0,lazy:!1,unverifiedLazy:!1,deprecated:!1,weak:!1,debugRedact:!1,retention:0}),Object.assign(Object.assign({$typeName:`google.protobuf.FieldOptions`},e),{targets:e.targets??[],editionDefaults:e.editionDefaults?.map(e=>Object.assign({$typeName:`google.protobuf.FieldOptions.EditionDefault`},e))??[],uninterpretedOption:[]}))}function Ln(e){return Object.assign(Object.create({visibility:0}),{$typeName:`google.protobuf.EnumDescriptorProto`,name:e.name,reservedName:[],reservedRange:[],value:e.value.map(e=>Object.assign({$typeName:`google.protobuf.EnumValueDescriptorProto`},e))})}function R(e,t,...n){return n.reduce((e,t)=>e.nestedMessages[t],e.messages[t])}var Rn=R(Mn({name:`google/protobuf/descriptor.proto`,package:`google.protobuf`,messageType:[{name:`FileDescriptorSet`,field:[{name:`file`,number:1,type:11,label:3,typeName:`.google.protobuf.FileDescriptorProto`}],extensionRange:[{start:536e6,end:536000001}]},{name:`FileDescriptorProto`,field:[{name:`name`,number:1,type:9,label:1},{name:`package`,number:2,type:9,label:1},{name:`dependency`,number:3,type:9,label:3},{name:`public_dependency`,number:10,type:5,label:3},{name:`weak_dependency`,number:11,type:5,label:3},{name:`option_dependency`,number:15,type:9,label:3},{name:`message_type`,number:4,type:11,label:3,typeName:`.google.protobuf.DescriptorProto`},{name:`enum_type`,number:5,type:11,label:3,typeName:`.google.protobuf.EnumDescriptorProto`},{name:`service`,number:6,type:11,label:3,typeName:`.google.protobuf.ServiceDescriptorProto`},{name:`extension`,number:7,type:11,label:3,typeName:`.google.protobuf.FieldDescriptorProto`},{name:`options`,number:8,type:11,label:1,typeName:`.google.protobuf.FileOptions`},{name:`source_code_info`,number:9,type:11,label:1,typeName:`.google.protobuf.SourceCodeInfo`},{name:`syntax`,number:12,type:9,label:1},{name:`edition`,number:14,type:14,label:1,typeName:`.google.protobuf.Edition`}]},{name:`DescriptorProto`,field:[{name:`name`,number:1,type:9,label:1},{name:`field`,number:2,type:11,label:3,typeName:`.google.protobuf.FieldDescriptorProto`},{name:`extension`,number:6,type:11,label:3,typeName:`.google.protobuf.FieldDescriptorProto`},{name:`nested_type`,number:3,type:11,label:3,typeName:`.google.protobuf.DescriptorProto`},{name:`enum_type`,number:4,type:11,label:3,typeName:`.google.protobuf.EnumDescriptorProto`},{name:`extension_range`,number:5,type:11,label:3,typeName:`.google.protobuf.DescriptorProto.ExtensionRange`},{name:`oneof_decl`,number:8,type:11,label:3,typeName:`.google.protobuf.OneofDescriptorProto`},{name:`options`,number:7,type:11,label:1,typeName:`.google.protobuf.MessageOptions`},{name:`reserved_range`,number:9,type:11,label:3,typeName:`.google.protobuf.DescriptorProto.ReservedRange`},{name:`reserved_name`,number:10,type:9,label:3},{name:`visibility`,number:11,type:14,label:1,typeName:`.google.protobuf.SymbolVisibility`}],nestedType:[{name:`ExtensionRange`,field:[{name:`start`,number:1,type:5,label:1},{name:`end`,number:2,type:5,label:1},{name:`options`,number:3,type:11,label:1,typeName:`.google.protobuf.ExtensionRangeOptions`}]},{name:`ReservedRange`,field:[{name:`start`,number:1,type:5,label:1},{name:`end`,number:2,type:5,label:1}]}]},{name:`ExtensionRangeOptions`,field:[{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`},{name:`declaration`,number:2,type:11,label:3,typeName:`.google.protobuf.ExtensionRangeOptions.Declaration`,options:{retention:2}},{name:`features`,number:50,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`verification`,number:3,type:14,label:1,typeName:`.google.protobuf.ExtensionRangeOptions.VerificationState`,defaultValue:`UNVERIFIED`,options:{retention:2}}],nestedType:[{name:`Declaration`,field:[{name:`number`,number:1,type:5,label:1},{name:`full_name`,number:2,type:9,label:1},{name:`type`,number:3,type:9,label:1},{name:`reserved`,number:5,type:8,label:1},{name:`repeated`,number:6,type:8,label:1}]}],enumType:[{name:`VerificationState`,value:[{name:`DECLARATION`,number:0},{name:`UNVERIFIED`,number:1}]}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`FieldDescriptorProto`,field:[{name:`name`,number:1,type:9,label:1},{name:`number`,number:3,type:5,label:1},{name:`label`,number:4,type:14,label:1,typeName:`.google.protobuf.FieldDescriptorProto.Label`},{name:`type`,number:5,type:14,label:1,typeName:`.google.protobuf.FieldDescriptorProto.Type`},{name:`type_name`,number:6,type:9,label:1},{name:`extendee`,number:2,type:9,label:1},{name:`default_value`,number:7,type:9,label:1},{name:`oneof_index`,number:9,type:5,label:1},{name:`json_name`,number:10,type:9,label:1},{name:`options`,number:8,type:11,label:1,typeName:`.google.protobuf.FieldOptions`},{name:`proto3_optional`,number:17,type:8,label:1}],enumType:[{name:`Type`,value:[{name:`TYPE_DOUBLE`,number:1},{name:`TYPE_FLOAT`,number:2},{name:`TYPE_INT64`,number:3},{name:`TYPE_UINT64`,number:4},{name:`TYPE_INT32`,number:5},{name:`TYPE_FIXED64`,number:6},{name:`TYPE_FIXED32`,number:7},{name:`TYPE_BOOL`,number:8},{name:`TYPE_STRING`,number:9},{name:`TYPE_GROUP`,number:10},{name:`TYPE_MESSAGE`,number:11},{name:`TYPE_BYTES`,number:12},{name:`TYPE_UINT32`,number:13},{name:`TYPE_ENUM`,number:14},{name:`TYPE_SFIXED32`,number:15},{name:`TYPE_SFIXED64`,number:16},{name:`TYPE_SINT32`,number:17},{name:`TYPE_SINT64`,number:18}]},{name:`Label`,value:[{name:`LABEL_OPTIONAL`,number:1},{name:`LABEL_REPEATED`,number:3},{name:`LABEL_REQUIRED`,number:2}]}]},{name:`OneofDescriptorProto`,field:[{name:`name`,number:1,type:9,label:1},{name:`options`,number:2,type:11,label:1,typeName:`.google.protobuf.OneofOptions`}]},{name:`EnumDescriptorProto`,field:[{name:`name`,number:1,type:9,label:1},{name:`value`,number:2,type:11,label:3,typeName:`.google.protobuf.EnumValueDescriptorProto`},{name:`options`,number:3,type:11,label:1,typeName:`.google.protobuf.EnumOptions`},{name:`reserved_range`,number:4,type:11,label:3,typeName:`.google.protobuf.EnumDescriptorProto.EnumReservedRange`},{name:`reserved_name`,number:5,type:9,label:3},{name:`visibility`,number:6,type:14,label:1,typeName:`.google.protobuf.SymbolVisibility`}],nestedType:[{name:`EnumReservedRange`,field:[{name:`start`,number:1,type:5,label:1},{name:`end`,number:2,type:5,label:1}]}]},{name:`EnumValueDescriptorProto`,field:[{name:`name`,number:1,type:9,label:1},{name:`number`,number:2,type:5,label:1},{name:`options`,number:3,type:11,label:1,typeName:`.google.protobuf.EnumValueOptions`}]},{name:`ServiceDescriptorProto`,field:[{name:`name`,number:1,type:9,label:1},{name:`method`,number:2,type:11,label:3,typeName:`.google.protobuf.MethodDescriptorProto`},{name:`options`,number:3,type:11,label:1,typeName:`.google.protobuf.ServiceOptions`}]},{name:`MethodDescriptorProto`,field:[{name:`name`,number:1,type:9,label:1},{name:`input_type`,number:2,type:9,label:1},{name:`output_type`,number:3,type:9,label:1},{name:`options`,number:4,type:11,label:1,typeName:`.google.protobuf.MethodOptions`},{name:`client_streaming`,number:5,type:8,label:1,defaultValue:`false`},{name:`server_streaming`,number:6,type:8,label:1,defaultValue:`false`}]},{name:`FileOptions`,field:[{name:`java_package`,number:1,type:9,label:1},{name:`java_outer_classname`,number:8,type:9,label:1},{name:`java_multiple_files`,number:10,type:8,label:1,defaultValue:`false`,options:{}},{name:`java_generate_equals_and_hash`,number:20,type:8,label:1,options:{deprecated:!0}},{name:`java_string_check_utf8`,number:27,type:8,label:1,defaultValue:`false`},{name:`optimize_for`,number:9,type:14,label:1,typeName:`.google.protobuf.FileOptions.OptimizeMode`,defaultValue:`SPEED`},{name:`go_package`,number:11,type:9,label:1},{name:`cc_generic_services`,number:16,type:8,label:1,defaultValue:`false`},{name:`java_generic_services`,number:17,type:8,label:1,defaultValue:`false`},{name:`py_generic_services`,number:18,type:8,label:1,defaultValue:`false`},{name:`deprecated`,number:23,type:8,label:1,defaultValue:`false`},{name:`cc_enable_arenas`,number:31,type:8,label:1,defaultValue:`true`,options:{}},{name:`objc_class_prefix`,number:36,type:9,label:1},{name:`csharp_namespace`,number:37,type:9,label:1},{name:`swift_prefix`,number:39,type:9,label:1},{name:`php_class_prefix`,number:40,type:9,label:1},{name:`php_namespace`,number:41,type:9,label:1},{name:`php_metadata_namespace`,number:44,type:9,label:1},{name:`ruby_package`,number:45,type:9,label:1},{name:`features`,number:50,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`}],enumType:[{name:`OptimizeMode`,value:[{name:`SPEED`,number:1},{name:`CODE_SIZE`,number:2},{name:`LITE_RUNTIME`,number:3}]}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`MessageOptions`,field:[{name:`message_set_wire_format`,number:1,type:8,label:1,defaultValue:`false`},{name:`no_standard_descriptor_accessor`,number:2,type:8,label:1,defaultValue:`false`},{name:`deprecated`,number:3,type:8,label:1,defaultValue:`false`},{name:`map_entry`,number:7,type:8,label:1},{name:`deprecated_legacy_json_field_conflicts`,number:11,type:8,label:1,options:{deprecated:!0}},{name:`features`,number:12,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`FieldOptions`,field:[{name:`ctype`,number:1,type:14,label:1,typeName:`.google.protobuf.FieldOptions.CType`,defaultValue:`STRING`},{name:`packed`,number:2,type:8,label:1},{name:`jstype`,number:6,type:14,label:1,typeName:`.google.protobuf.FieldOptions.JSType`,defaultValue:`JS_NORMAL`},{name:`lazy`,number:5,type:8,label:1,defaultValue:`false`},{name:`unverified_lazy`,number:15,type:8,label:1,defaultValue:`false`},{name:`deprecated`,number:3,type:8,label:1,defaultValue:`false`},{name:`weak`,number:10,type:8,label:1,defaultValue:`false`,options:{deprecated:!0}},{name:`debug_redact`,number:16,type:8,label:1,defaultValue:`false`},{name:`retention`,number:17,type:14,label:1,typeName:`.google.protobuf.FieldOptions.OptionRetention`},{name:`targets`,number:19,type:14,label:3,typeName:`.google.protobuf.FieldOptions.OptionTargetType`},{name:`edition_defaults`,number:20,type:11,label:3,typeName:`.google.protobuf.FieldOptions.EditionDefault`},{name:`features`,number:21,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`feature_support`,number:22,type:11,label:1,typeName:`.google.protobuf.FieldOptions.FeatureSupport`},{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`}],nestedType:[{name:`EditionDefault`,field:[{name:`edition`,number:3,type:14,label:1,typeName:`.google.protobuf.Edition`},{name:`value`,number:2,type:9,label:1}]},{name:`FeatureSupport`,field:[{name:`edition_introduced`,number:1,type:14,label:1,typeName:`.google.protobuf.Edition`},{name:`edition_deprecated`,number:2,type:14,label:1,typeName:`.google.protobuf.Edition`},{name:`deprecation_warning`,number:3,type:9,label:1},{name:`edition_removed`,number:4,type:14,label:1,typeName:`.google.protobuf.Edition`},{name:`removal_error`,number:5,type:9,label:1}]}],enumType:[{name:`CType`,value:[{name:`STRING`,number:0},{name:`CORD`,number:1},{name:`STRING_PIECE`,number:2}]},{name:`JSType`,value:[{name:`JS_NORMAL`,number:0},{name:`JS_STRING`,number:1},{name:`JS_NUMBER`,number:2}]},{name:`OptionRetention`,value:[{name:`RETENTION_UNKNOWN`,number:0},{name:`RETENTION_RUNTIME`,number:1},{name:`RETENTION_SOURCE`,number:2}]},{name:`OptionTargetType`,value:[{name:`TARGET_TYPE_UNKNOWN`,number:0},{name:`TARGET_TYPE_FILE`,number:1},{name:`TARGET_TYPE_EXTENSION_RANGE`,number:2},{name:`TARGET_TYPE_MESSAGE`,number:3},{name:`TARGET_TYPE_FIELD`,number:4},{name:`TARGET_TYPE_ONEOF`,number:5},{name:`TARGET_TYPE_ENUM`,number:6},{name:`TARGET_TYPE_ENUM_ENTRY`,number:7},{name:`TARGET_TYPE_SERVICE`,number:8},{name:`TARGET_TYPE_METHOD`,number:9}]}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`OneofOptions`,field:[{name:`features`,number:1,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`EnumOptions`,field:[{name:`allow_alias`,number:2,type:8,label:1},{name:`deprecated`,number:3,type:8,label:1,defaultValue:`false`},{name:`deprecated_legacy_json_field_conflicts`,number:6,type:8,label:1,options:{deprecated:!0}},{name:`features`,number:7,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`EnumValueOptions`,field:[{name:`deprecated`,number:1,type:8,label:1,defaultValue:`false`},{name:`features`,number:2,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`debug_redact`,number:3,type:8,label:1,defaultValue:`false`},{name:`feature_support`,number:4,type:11,label:1,typeName:`.google.protobuf.FieldOptions.FeatureSupport`},{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`ServiceOptions`,field:[{name:`features`,number:34,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`deprecated`,number:33,type:8,label:1,defaultValue:`false`},{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`MethodOptions`,field:[{name:`deprecated`,number:33,type:8,label:1,defaultValue:`false`},{name:`idempotency_level`,number:34,type:14,label:1,typeName:`.google.protobuf.MethodOptions.IdempotencyLevel`,defaultValue:`IDEMPOTENCY_UNKNOWN`},{name:`features`,number:35,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`uninterpreted_option`,number:999,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption`}],enumType:[{name:`IdempotencyLevel`,value:[{name:`IDEMPOTENCY_UNKNOWN`,number:0},{name:`NO_SIDE_EFFECTS`,number:1},{name:`IDEMPOTENT`,number:2}]}],extensionRange:[{start:990,end:999},{start:1e3,end:536870912}]},{name:`UninterpretedOption`,field:[{name:`name`,number:2,type:11,label:3,typeName:`.google.protobuf.UninterpretedOption.NamePart`},{name:`identifier_value`,number:3,type:9,label:1},{name:`positive_int_value`,number:4,type:4,label:1},{name:`negative_int_value`,number:5,type:3,label:1},{name:`double_value`,number:6,type:1,label:1},{name:`string_value`,number:7,type:12,label:1},{name:`aggregate_value`,number:8,type:9,label:1}],nestedType:[{name:`NamePart`,field:[{name:`name_part`,number:1,type:9,label:2},{name:`is_extension`,number:2,type:8,label:2}]}]},{name:`FeatureSet`,field:[{name:`field_presence`,number:1,type:14,label:1,typeName:`.google.protobuf.FeatureSet.FieldPresence`,options:{retention:1,targets:[4,1],editionDefaults:[{value:`EXPLICIT`,edition:900},{value:`IMPLICIT`,edition:999},{value:`EXPLICIT`,edition:1e3}]}},{name:`enum_type`,number:2,type:14,label:1,typeName:`.google.protobuf.FeatureSet.EnumType`,options:{retention:1,targets:[6,1],editionDefaults:[{value:`CLOSED`,edition:900},{value:`OPEN`,edition:999}]}},{name:`repeated_field_encoding`,number:3,type:14,label:1,typeName:`.google.protobuf.FeatureSet.RepeatedFieldEncoding`,options:{retention:1,targets:[4,1],editionDefaults:[{value:`EXPANDED`,edition:900},{value:`PACKED`,edition:999}]}},{name:`utf8_validation`,number:4,type:14,label:1,typeName:`.google.protobuf.FeatureSet.Utf8Validation`,options:{retention:1,targets:[4,1],editionDefaults:[{value:`NONE`,edition:900},{value:`VERIFY`,edition:999}]}},{name:`message_encoding`,number:5,type:14,label:1,typeName:`.google.protobuf.FeatureSet.MessageEncoding`,options:{retention:1,targets:[4,1],editionDefaults:[{value:`LENGTH_PREFIXED`,edition:900}]}},{name:`json_format`,number:6,type:14,label:1,typeName:`.google.protobuf.FeatureSet.JsonFormat`,options:{retention:1,targets:[3,6,1],editionDefaults:[{value:`LEGACY_BEST_EFFORT`,edition:900},{value:`ALLOW`,edition:999}]}},{name:`enforce_naming_style`,number:7,type:14,label:1,typeName:`.google.protobuf.FeatureSet.EnforceNamingStyle`,options:{retention:2,targets:[1,2,3,4,5,6,7,8,9],editionDefaults:[{value:`STYLE_LEGACY`,edition:900},{value:`STYLE2024`,edition:1001},{value:`STYLE2026`,edition:1002}]}},{name:`default_symbol_visibility`,number:8,type:14,label:1,typeName:`.google.protobuf.FeatureSet.VisibilityFeature.DefaultSymbolVisibility`,options:{retention:2,targets:[1],editionDefaults:[{value:`EXPORT_ALL`,edition:900},{value:`EXPORT_TOP_LEVEL`,edition:1001},{value:`STRICT`,edition:1002}]}},{name:`enforce_proto_limits`,number:9,type:14,label:1,typeName:`.google.protobuf.FeatureSet.ProtoLimitsFeature.EnforceProtoLimits`,options:{retention:2,targets:[6,3,4,5],editionDefaults:[{value:`LEGACY_NO_EXPLICIT_LIMITS`,edition:900},{value:`PROTO_LIMITS2026`,edition:1002}]}}],nestedType:[{name:`VisibilityFeature`,enumType:[{name:`DefaultSymbolVisibility`,value:[{name:`DEFAULT_SYMBOL_VISIBILITY_UNKNOWN`,number:0},{name:`EXPORT_ALL`,number:1},{name:`EXPORT_TOP_LEVEL`,number:2},{name:`LOCAL_ALL`,number:3},{name:`STRICT`,number:4}]}]},{name:`ProtoLimitsFeature`,enumType:[{name:`EnforceProtoLimits`,value:[{name:`PROTO_LIMITS_UNKNOWN`,number:0},{name:`LEGACY_NO_EXPLICIT_LIMITS`,number:1},{name:`PROTO_LIMITS2026`,number:2}]}]}],enumType:[{name:`FieldPresence`,value:[{name:`FIELD_PRESENCE_UNKNOWN`,number:0},{name:`EXPLICIT`,number:1},{name:`IMPLICIT`,number:2},{name:`LEGACY_REQUIRED`,number:3}]},{name:`EnumType`,value:[{name:`ENUM_TYPE_UNKNOWN`,number:0},{name:`OPEN`,number:1},{name:`CLOSED`,number:2}]},{name:`RepeatedFieldEncoding`,value:[{name:`REPEATED_FIELD_ENCODING_UNKNOWN`,number:0},{name:`PACKED`,number:1},{name:`EXPANDED`,number:2}]},{name:`Utf8Validation`,value:[{name:`UTF8_VALIDATION_UNKNOWN`,number:0},{name:`VERIFY`,number:2},{name:`NONE`,number:3}]},{name:`MessageEncoding`,value:[{name:`MESSAGE_ENCODING_UNKNOWN`,number:0},{name:`LENGTH_PREFIXED`,number:1},{name:`DELIMITED`,number:2}]},{name:`JsonFormat`,value:[{name:`JSON_FORMAT_UNKNOWN`,number:0},{name:`ALLOW`,number:1},{name:`LEGACY_BEST_EFFORT`,number:2}]},{name:`EnforceNamingStyle`,value:[{name:`ENFORCE_NAMING_STYLE_UNKNOWN`,number:0},{name:`STYLE2024`,number:1},{name:`STYLE_LEGACY`,number:2},{name:`STYLE2026`,number:3}]}],extensionRange:[{start:1e3,end:9995},{start:9995,end:1e4},{start:1e4,end:10001}]},{name:`FeatureSetDefaults`,field:[{name:`defaults`,number:1,type:11,label:3,typeName:`.google.protobuf.FeatureSetDefaults.FeatureSetEditionDefault`},{name:`minimum_edition`,number:4,type:14,label:1,typeName:`.google.protobuf.Edition`},{name:`maximum_edition`,number:5,type:14,label:1,typeName:`.google.protobuf.Edition`}],nestedType:[{name:`FeatureSetEditionDefault`,field:[{name:`edition`,number:3,type:14,label:1,typeName:`.google.protobuf.Edition`},{name:`overridable_features`,number:4,type:11,label:1,typeName:`.google.protobuf.FeatureSet`},{name:`fixed_features`,number:5,type:11,label:1,typeName:`.google.protobuf.FeatureSet`}]}]},{name:`SourceCodeInfo`,field:[{name:`location`,number:1,type:11,label:3,typeName:`.google.protobuf.SourceCodeInfo.Location`}],nestedType:[{name:`Location`,field:[{name:`path`,number:1,type:5,label:3,options:{packed:!0}},{name:`span`,number:2,type:5,label:3,options:{packed:!0}},{name:`leading_comments`,number:3,type:9,label:1},{name:`trailing_comments`,number:4,type:9,label:1},{name:`leading_detached_comments`,number:6,type:9,label:3}]}],extensionRange:[{start:536e6,end:536000001}]},{name:`GeneratedCodeInfo`,field:[{name:`annotation`,number:1,type:11,label:3,typeName:`.google.protobuf.GeneratedCodeInfo.Annotation`}],nestedType:[{name:`Annotation`,field:[{name:`path`,number:1,type:5,label:3,options:{packed:!0}},{name:`source_file`,number:2,type:9,label:1},{name:`begin`,number:3,type:5,label:1},{name:`end`,number:4,type:5,label:1},{name:`semantic`,number:5,type:14,label:1,typeName:`.google.protobuf.GeneratedCodeInfo.Annotation.Semantic`}],enumType:[{name:`Semantic`,value:[{name:`NONE`,number:0},{name:`SET`,number:1},{name:`ALIAS`,number:2}]}]}]}],enumType:[{name:`Edition`,value:[{name:`EDITION_UNKNOWN`,number:0},{name:`EDITION_LEGACY`,number:900},{name:`EDITION_PROTO2`,number:998},{name:`EDITION_PROTO3`,number:999},{name:`EDITION_2023`,number:1e3},{name:`EDITION_2024`,number:1001},{name:`EDITION_2026`,number:1002},{name:`EDITION_UNSTABLE`,number:9999},{name:`EDITION_1_TEST_ONLY`,number:1},{name:`EDITION_2_TEST_ONLY`,number:2},{name:`EDITION_99997_TEST_ONLY`,number:99997},{name:`EDITION_99998_TEST_ONLY`,number:99998},{name:`EDITION_99999_TEST_ONLY`,number:99999},{name:`EDITION_MAX`,number:0x7fffffff}]},{name:`SymbolVisibility`,value:[{name:`VISIBILITY_UNSET`,number:0},{name:`VISIBILITY_LOCAL`,number:1},{name:`VISIBILITY_EXPORT`,number:2}]}]}),1),zn;(function(e){e[e.DECLARATION=0]=`DECLARATION`,e[e.UNVERIFIED=1]=`UNVERIFIED`})(zn||={});var Bn;(function(e){e[e.DOUBLE=1]=`DOUBLE`,e[e.FLOAT=2]=`FLOAT`,e[e.INT64=3]=`INT64`,e[e.UINT64=4]=`UINT64`,e[e.INT32=5]=`INT32`,e[e.FIXED64=6]=`FIXED64`,e[e.FIXED32=7]=`FIXED32`,e[e.BOOL=8]=`BOOL`,e[e.STRING=9]=`STRING`,e[e.GROUP=10]=`GROUP`,e[e.MESSAGE=11]=`MESSAGE`,e[e.BYTES=12]=`BYTES`,e[e.UINT32=13]=`UINT32`,e[e.ENUM=14]=`ENUM`,e[e.SFIXED32=15]=`SFIXED32`,e[e.SFIXED64=16]=`SFIXED64`,e[e.SINT32=17]=`SINT32`,e[e.SINT64=18]=`SINT64`})(Bn||={});var Vn;(function(e){e[e.OPTIONAL=1]=`OPTIONAL`,e[e.REPEATED=3]=`REPEATED`,e[e.REQUIRED=2]=`REQUIRED`})(Vn||={});var Hn;(function(e){e[e.SPEED=1]=`SPEED`,e[e.CODE_SIZE=2]=`CODE_SIZE`,e[e.LITE_RUNTIME=3]=`LITE_RUNTIME`})(Hn||={});var Un;(function(e){e[e.STRING=0]=`STRING`,e[e.CORD=1]=`CORD`,e[e.STRING_PIECE=2]=`STRING_PIECE`})(Un||={});var Wn;(function(e){e[e.JS_NORMAL=0]=`JS_NORMAL`,e[e.JS_STRING=1]=`JS_STRING`,e[e.JS_NUMBER=2]=`JS_NUMBER`})(Wn||={});var Gn;(function(e){e[e.RETENTION_UNKNOWN=0]=`RETENTION_UNKNOWN`,e[e.RETENTION_RUNTIME=1]=`RETENTION_RUNTIME`,e[e.RETENTION_SOURCE=2]=`RETENTION_SOURCE`})(Gn||={});var Kn;(function(e){e[e.TARGET_TYPE_UNKNOWN=0]=`TARGET_TYPE_UNKNOWN`,e[e.TARGET_TYPE_FILE=1]=`TARGET_TYPE_FILE`,e[e.TARGET_TYPE_EXTENSION_RANGE=2]=`TARGET_TYPE_EXTENSION_RANGE`,e[e.TARGET_TYPE_MESSAGE=3]=`TARGET_TYPE_MESSAGE`,e[e.TARGET_TYPE_FIELD=4]=`TARGET_TYPE_FIELD`,e[e.TARGET_TYPE_ONEOF=5]=`TARGET_TYPE_ONEOF`,e[e.TARGET_TYPE_ENUM=6]=`TARGET_TYPE_ENUM`,e[e.TARGET_TYPE_ENUM_ENTRY=7]=`TARGET_TYPE_ENUM_ENTRY`,e[e.TARGET_TYPE_SERVICE=8]=`TARGET_TYPE_SERVICE`,e[e.TARGET_TYPE_METHOD=9]=`TARGET_TYPE_METHOD`})(Kn||={});var qn;(function(e){e[e.IDEMPOTENCY_UNKNOWN=0]=`IDEMPOTENCY_UNKNOWN`,e[e.NO_SIDE_EFFECTS=1]=`NO_SIDE_EFFECTS`,e[e.IDEMPOTENT=2]=`IDEMPOTENT`})(qn||={});var Jn;(function(e){e[e.DEFAULT_SYMBOL_VISIBILITY_UNKNOWN=0]=`DEFAULT_SYMBOL_VISIBILITY_UNKNOWN`,e[e.EXPORT_ALL=1]=`EXPORT_ALL`,e[e.EXPORT_TOP_LEVEL=2]=`EXPORT_TOP_LEVEL`,e[e.LOCAL_ALL=3]=`LOCAL_ALL`,e[e.STRICT=4]=`STRICT`})(Jn||={});var Yn;(function(e){e[e.PROTO_LIMITS_UNKNOWN=0]=`PROTO_LIMITS_UNKNOWN`,e[e.LEGACY_NO_EXPLICIT_LIMITS=1]=`LEGACY_NO_EXPLICIT_LIMITS`,e[e.PROTO_LIMITS2026=2]=`PROTO_LIMITS2026`})(Yn||={});var Xn;(function(e){e[e.FIELD_PRESENCE_UNKNOWN=0]=`FIELD_PRESENCE_UNKNOWN`,e[e.EXPLICIT=1]=`EXPLICIT`,e[e.IMPLICIT=2]=`IMPLICIT`,e[e.LEGACY_REQUIRED=3]=`LEGACY_REQUIRED`})(Xn||={});var Zn;(function(e){e[e.ENUM_TYPE_UNKNOWN=0]=`ENUM_TYPE_UNKNOWN`,e[e.OPEN=1]=`OPEN`,e[e.CLOSED=2]=`CLOSED`})(Zn||={});var Qn;(function(e){e[e.REPEATED_FIELD_ENCODING_UNKNOWN=0]=`REPEATED_FIELD_ENCODING_UNKNOWN`,e[e.PACKED=1]=`PACKED`,e[e.EXPANDED=2]=`EXPANDED`})(Qn||={});var $n;(function(e){e[e.UTF8_VALIDATION_UNKNOWN=0]=`UTF8_VALIDATION_UNKNOWN`,e[e.VERIFY=2]=`VERIFY`,e[e.NONE=3]=`NONE`})($n||={});var er;(function(e){e[e.MESSAGE_ENCODING_UNKNOWN=0]=`MESSAGE_ENCODING_UNKNOWN`,e[e.LENGTH_PREFIXED=1]=`LENGTH_PREFIXED`,e[e.DELIMITED=2]=`DELIMITED`})(er||={});var tr;(function(e){e[e.JSON_FORMAT_UNKNOWN=0]=`JSON_FORMAT_UNKNOWN`,e[e.ALLOW=1]=`ALLOW`,e[e.LEGACY_BEST_EFFORT=2]=`LEGACY_BEST_EFFORT`})(tr||={});var nr;(function(e){e[e.ENFORCE_NAMING_STYLE_UNKNOWN=0]=`ENFORCE_NAMING_STYLE_UNKNOWN`,e[e.STYLE2024=1]=`STYLE2024`,e[e.STYLE_LEGACY=2]=`STYLE_LEGACY`,e[e.STYLE2026=3]=`STYLE2026`})(nr||={});var rr;(function(e){e[e.NONE=0]=`NONE`,e[e.SET=1]=`SET`,e[e.ALIAS=2]=`ALIAS`})(rr||={});var ir;(function(e){e[e.EDITION_UNKNOWN=0]=`EDITION_UNKNOWN`,e[e.EDITION_LEGACY=900]=`EDITION_LEGACY`,e[e.EDITION_PROTO2=998]=`EDITION_PROTO2`,e[e.EDITION_PROTO3=999]=`EDITION_PROTO3`,e[e.EDITION_2023=1e3]=`EDITION_2023`,e[e.EDITION_2024=1001]=`EDITION_2024`,e[e.EDITION_2026=1002]=`EDITION_2026`,e[e.EDITION_UNSTABLE=9999]=`EDITION_UNSTABLE`,e[e.EDITION_1_TEST_ONLY=1]=`EDITION_1_TEST_ONLY`,e[e.EDITION_2_TEST_ONLY=2]=`EDITION_2_TEST_ONLY`,e[e.EDITION_99997_TEST_ONLY=99997]=`EDITION_99997_TEST_ONLY`,e[e.EDITION_99998_TEST_ONLY=99998]=`EDITION_99998_TEST_ONLY`,e[e.EDITION_99999_TEST_ONLY=99999]=`EDITION_99999_TEST_ONLY`,e[e.EDITION_MAX=0x7fffffff]=`EDITION_MAX`})(ir||={});var ar;(function(e){e[e.VISIBILITY_UNSET=0]=`VISIBILITY_UNSET`,e[e.VISIBILITY_LOCAL=1]=`VISIBILITY_LOCAL`,e[e.VISIBILITY_EXPORT=2]=`VISIBILITY_EXPORT`})(ar||={});function or(e){return Object.assign(Object.assign({readUnknownFields:!0,recursionLimit:100},e),{depth:0})}function sr(e,t,n){let r=N(e);return lr(e).read(r,new Ne(t),or(n),t.byteLength),r}var cr=new WeakMap;function lr(e){let t=cr.get(e);return t===void 0&&(t=ur(e)),t}function ur(e){let t=String(e),n=new Map,r={read:dr(t,n),readGroup:fr(t,n)};cr.set(e,r);for(let t of e.fields)n.set(t.number,mr(t));return r}function dr(e,t){return(n,r,i,a)=>{if(++i.depth>i.recursionLimit)throw Error(`cannot decode ${e} from binary: maximum recursion depth of ${i.recursionLimit} reached`);let o=r.pos+a,s=n.$unknown??[];for(;r.pos<o;){let[e,a]=r.tag(),o=t.get(e);if(o===void 0){let t=r.skip(a,e,i.recursionLimit-i.depth);i.readUnknownFields&&s.push({no:e,wireType:a,data:t})}else o(n,r,i,a)}s.length>0&&(n.$unknown=s),i.depth--}}function fr(e,t){return(n,r,i,a)=>{if(++i.depth>i.recursionLimit)throw Error(`cannot decode ${e} from binary: maximum recursion depth of ${i.recursionLimit} reached`);let o,s,c=n.$unknown??[];for(;r.pos<r.len&&([o,s]=r.tag(),s!=I.EndGroup);){let e=t.get(o);if(e===void 0){let e=r.skip(s,o,i.recursionLimit-i.depth);i.readUnknownFields&&c.push({no:o,wireType:s,data:e})}else e(n,r,i,s)}if(s!=I.EndGroup||o!==a)throw Error(`invalid end group tag`);c.length>0&&(n.$unknown=c),i.depth--}}function pr(e,t,n,r,i){mr(n)(e[b],t,i,r)}function mr(e){switch(e.fieldKind){case`scalar`:return hr(e);case`enum`:return gr(e);case`message`:return _r(e);case`list`:return yr(e);case`map`:return br(e)}}function hr(e){let t=xr(e.scalar,e.utf8Validation,e.longAsString),n=e.localName;if(e.oneof){let r=e.oneof.localName;return(e,i)=>{e[r]={case:n,value:t(i)}}}return(e,r)=>{e[n]=t(r)}}function gr(e){let t=e.localName,n=e.oneof?.localName;if(e.enum.open)return n===void 0?(e,n)=>{e[t]=n.int32()}:(e,r)=>{e[n]={case:t,value:r.int32()}};let r=e.enum.values,i=e.number;return(e,a,o,s)=>{let c=a.int32();if(r.some(e=>e.number===c))n===void 0?e[t]=c:e[n]={case:t,value:c};else if(o.readUnknownFields){let t=[];d(c,t);let n=e.$unknown??[];n.push({no:i,wireType:s,data:new Uint8Array(t)}),e.$unknown=n}}}function _r(e){let t=e.localName,{toMessage:n,toLocal:r}=Je(e),i=vr(e);if(e.oneof){let a=e.oneof.localName;return(e,o,s)=>{let c=e[a],l=n(c.case===t?c.value:void 0);i(l,o,s),e[a]={case:t,value:r(l)}}}return(e,a,o)=>{let s=n(e[t]);i(s,a,o),e[t]=r(s)}}function vr(e){let t=lr(e.message);if(e.delimitedEncoding){let n=e.number;return(e,r,i)=>t.readGroup(e,r,i,n)}return(e,n,r)=>t.read(e,n,r,n.uint32())}function yr(e){let n=e.localName;if(e.listKind==`message`){let{toMessage:t,toLocal:r}=Je(e),i=vr(e);return(e,a,o)=>{let s=t(void 0);i(s,a,o),e[n].push(r(s))}}let r=e.listKind==`enum`?t.INT32:e.scalar,i=e.listKind==`scalar`&&e.longAsString,a=xr(r,e.utf8Validation,i),o=r!=t.STRING&&r!=t.BYTES;return(e,t,r,i)=>{let s=e[n];if(i==I.LengthDelimited&&o){let e=t.uint32()+t.pos;for(;t.pos<e;)s.push(a(t))}else s.push(a(t))}}function br(e){let n=e.localName,r=xr(e.mapKey,e.utf8Validation,!1),i=_(e.mapKey,!1),a,o;switch(e.mapKind){case`scalar`:{let n=e.scalar,r=xr(n,e.utf8Validation,!1);if(a=e=>r(e),n==t.BYTES)o=()=>new Uint8Array;else{let e=_(n,!1);o=()=>e}break}case`enum`:{let t=e.enum.values[0].number;a=e=>e.int32(),o=()=>t;break}case`message`:{let{toMessage:t,toLocal:n}=Je(e),r=lr(e.message).read;a=(e,i,a)=>{let o=t(a);return r(o,e,i,e.uint32()),n(o)},o=()=>n(t(void 0));break}}return(e,t,s)=>{let c=e[n],l,u,d=t.uint32(),f=t.pos+d;for(;t.pos<f;){let[e,n]=t.tag();switch(e){case 1:l=r(t);break;case 2:u=a(t,s,u);break;default:t.skip(n,e,s.recursionLimit-s.depth)}}l===void 0&&(l=i),u===void 0&&(u=o()),E(c,l,u)}}function xr(e,n,r){switch(e){case t.STRING:return e=>e.string(n);case t.BOOL:return e=>e.bool();case t.DOUBLE:return e=>e.double();case t.FLOAT:return e=>e.float();case t.INT32:return e=>e.int32();case t.INT64:return r?e=>String(e.int64()):e=>e.int64();case t.UINT64:return r?e=>String(e.uint64()):e=>e.uint64();case t.FIXED64:return r?e=>String(e.fixed64()):e=>e.fixed64();case t.BYTES:return e=>e.bytes();case t.FIXED32:return e=>e.fixed32();case t.SFIXED32:return e=>e.sfixed32();case t.SFIXED64:return r?e=>String(e.sfixed64()):e=>e.sfixed64();case t.SINT64:return r?e=>String(e.sint64()):e=>e.sint64();case t.UINT32:return e=>e.uint32();case t.SINT32:return e=>e.sint32()}}function Sr(e,t){let n=sr(Rn,_t(e));return n.messageType.forEach(jt),n.dependency=t?.map(e=>e.proto.name)??[],It(n,e=>t?.find(t=>t.proto.name===e)).getFile(n.name)}var Cr=Sr(`Chlnb29nbGUvcHJvdG9idWYvYW55LnByb3RvEg9nb29nbGUucHJvdG9idWYiJgoDQW55EhAKCHR5cGVfdXJsGAEgASgJEg0KBXZhbHVlGAIgASgMQnYKE2NvbS5nb29nbGUucHJvdG9idWZCCEFueVByb3RvUAFaLGdvb2dsZS5nb2xhbmcub3JnL3Byb3RvYnVmL3R5cGVzL2tub3duL2FueXBiogIDR1BCqgIeR29vZ2xlLlByb3RvYnVmLldlbGxLbm93blR5cGVzYgZwcm90bzM`),wr=R(Cr,0),Tr=2,Er=3,Dr={writeUnknownFields:!0};function Or(e){return e?Object.assign(Object.assign({},Dr),e):Dr}function kr(e,t,n){let r=new Ee;return jr(e)(r,Or(n),t),r.finish()}var Ar=new WeakMap;function jr(e){let t=Ar.get(e);return t===void 0&&(t=Mr(e)),t}function Mr(e){let t=e.typeName,n=e.fields.concat().sort((e,t)=>e.number-t.number),r=n[0],i=[],a=(e,n,a)=>{if(a.$typeName!==t&&r!==void 0)throw new F(r,`cannot use ${r} with message ${a.$typeName}`,`ForeignFieldError`);for(let t=0;t<i.length;t++)i[t](e,n,a);let o=a.$unknown;if(o!==void 0&&n.writeUnknownFields)for(let t=0;t<o.length;t++){let{no:n,wireType:r,data:i}=o[t];e.tag(n,r).raw(i)}};Ar.set(e,a);for(let e of n)i.push(Nr(e));return a}function Nr(e){switch(e.fieldKind){case`message`:case`scalar`:case`enum`:return Pr(e);case`list`:return Ir(e);case`map`:return Lr(e)}}function Pr(e){let n=Fr(e),r=e.localName;if(e.oneof){let t=e.oneof.localName;return(e,i,a)=>{let o=a[t];o.case===r&&n(e,i,o.value)}}if(e.presence!=Tr){let t=e.presence==Er?`cannot encode ${e} to binary: required field not set`:void 0;return(e,i,a)=>{let o=a[r];if(o!==void 0&&Object.prototype.hasOwnProperty.call(a,r))n(e,i,o);else if(t!==void 0)throw Error(t)}}if(e.fieldKind==`enum`){let t=e.enum.values[0].number;return(e,i,a)=>{let o=a[r];o!==t&&n(e,i,o)}}switch(e.scalar){case t.BOOL:return(e,t,i)=>{let a=i[r];a!==!1&&n(e,t,a)};case t.STRING:return(e,t,i)=>{let a=i[r];a!==``&&n(e,t,a)};case t.BYTES:return(e,t,i)=>{let a=i[r];(!(a instanceof Uint8Array)||a.byteLength>0)&&n(e,t,a)};case t.DOUBLE:case t.FLOAT:return(e,t,i)=>{let a=i[r];Object.is(a,0)||n(e,t,a)};default:return(e,t,i)=>{let a=i[r];a!=0&&n(e,t,a)}}}function Fr(e){switch(e.fieldKind){case`message`:{let{toMessage:t}=Je(e),n=Ur(e);return(e,r,i)=>{n(e,r,t(i))}}case`scalar`:case`enum`:{let n=e.fieldKind==`enum`?t.INT32:e.scalar,r=e.number,i=Wr(n),a=Br(n,e.parent.typeName,e.name);return(e,t,n)=>{e.tag(r,i),a(e,n)}}}}function Ir(e){let n=e.localName,r=e.number;switch(e.listKind){case`message`:{let{toMessage:t}=Je(e),r=Ur(e);return(e,i,a)=>{let o=a[n];for(let n=0;n<o.length;n++)r(e,i,t(o[n]))}}case`scalar`:case`enum`:{let i=e.listKind==`enum`?t.INT32:e.scalar,a=Br(i,e.parent.typeName,e.name);if(e.packed)return(e,t,i)=>{let o=i[n];if(o.length!=0){e.tag(r,I.LengthDelimited).fork();for(let t=0;t<o.length;t++)a(e,o[t]);e.join()}};let o=Wr(i);return(e,t,i)=>{let s=i[n];for(let t=0;t<s.length;t++)e.tag(r,o),a(e,s[t])}}}}function Lr(e){let n=e.localName,r=e.number,i=Rr(e);if(e.mapKind==`message`){let{toMessage:t}=Je(e),a=jr(e.message);return(e,o,s)=>{let c=s[n],l=Object.keys(c);for(let n=0;n<l.length;n++){let s=l[n];e.tag(r,I.LengthDelimited).fork(),i(e,s),e.tag(2,I.LengthDelimited).fork(),a(e,o,t(c[s])),e.join(),e.join()}}}let a=e.mapKind==`enum`?t.INT32:e.scalar,o=Wr(a),s=Br(a,e.parent.typeName,e.name);return(e,t,a)=>{let c=a[n],l=Object.keys(c);for(let t=0;t<l.length;t++){let n=l[t];e.tag(r,I.LengthDelimited).fork(),i(e,n),e.tag(2,o),s(e,c[n]),e.join()}}}function Rr(e){let t=Wr(e.mapKey),n=Br(e.mapKey,e.parent.typeName,e.name),r=zr(e.mapKey);return(e,i)=>{e.tag(1,t),n(e,r(i))}}function zr(e){switch(e){case t.STRING:return e=>e;case t.BOOL:return e=>e===`true`||e!==`false`&&e;case t.UINT64:case t.FIXED64:return e=>{try{return p.uParse(e)}catch{return e}};case t.INT64:case t.SFIXED64:case t.SINT64:return e=>{try{return p.parse(e)}catch{return e}};default:return e=>{let t=Number.parseInt(e);return Number.isFinite(t)?t:e}}}function Br(e,t,n){let r=Vr(e);return(e,i)=>{try{r(e,i)}catch(e){throw e instanceof Error?Error(`cannot encode field ${t}.${n} to binary: ${e.message}`):e}}}function Vr(e){switch(e){case t.STRING:return(e,t)=>e.string(t);case t.BOOL:return(e,t)=>e.bool(t);case t.DOUBLE:return(e,t)=>e.double(t);case t.FLOAT:return(e,t)=>e.float(t);case t.INT32:return(e,t)=>e.int32(t);case t.INT64:return(e,t)=>e.int64(t);case t.UINT64:return(e,t)=>e.uint64(t);case t.FIXED64:return(e,t)=>e.fixed64(t);case t.BYTES:return(e,t)=>e.bytes(t);case t.FIXED32:return(e,t)=>e.fixed32(t);case t.SFIXED32:return(e,t)=>e.sfixed32(t);case t.SFIXED64:return(e,t)=>e.sfixed64(t);case t.SINT64:return(e,t)=>e.sint64(t);case t.UINT32:return(e,t)=>e.uint32(t);case t.SINT32:return(e,t)=>e.sint32(t)}}function Hr(e,t,n,r){Nr(r)(e,t,n[b])}function Ur(e){let t=e.number,n=jr(e.message);return e.delimitedEncoding?(e,r,i)=>{e.tag(t,I.StartGroup),n(e,r,i),e.tag(t,I.EndGroup)}:(e,r,i)=>{e.tag(t,I.LengthDelimited).fork(),n(e,r,i),e.join()}}function Wr(e){switch(e){case t.BYTES:case t.STRING:return I.LengthDelimited;case t.DOUBLE:case t.FIXED64:case t.SFIXED64:return I.Bit64;case t.FIXED32:case t.SFIXED32:case t.FLOAT:return I.Bit32;default:return I.Varint}}function Gr(e,t,n){let r=!1;return n||(n=N(wr),r=!0),n.value=kr(e,t),n.typeUrl=Jr(t.$typeName),r?n:void 0}function Kr(e,t){return e.typeUrl!==``&&(typeof t==`string`?t:t.typeName)===Yr(e.typeUrl)}function qr(e,t){if(e.typeUrl===``)return;let n=t.kind==`message`?t:t.getMessage(Yr(e.typeUrl));if(n&&Kr(e,n))return sr(n,e.value)}function Jr(e){return`type.googleapis.com/${e}`}function Yr(e){let t=e.lastIndexOf(`/`),n=t>=0?e.substring(t+1):e;if(!n.length)throw Error(`invalid type url: ${e}`);return n}var Xr=Sr(`Chxnb29nbGUvcHJvdG9idWYvc3RydWN0LnByb3RvEg9nb29nbGUucHJvdG9idWYihAEKBlN0cnVjdBIzCgZmaWVsZHMYASADKAsyIy5nb29nbGUucHJvdG9idWYuU3RydWN0LkZpZWxkc0VudHJ5GkUKC0ZpZWxkc0VudHJ5EgsKA2tleRgBIAEoCRIlCgV2YWx1ZRgCIAEoCzIWLmdvb2dsZS5wcm90b2J1Zi5WYWx1ZToCOAEi6gEKBVZhbHVlEjAKCm51bGxfdmFsdWUYASABKA4yGi5nb29nbGUucHJvdG9idWYuTnVsbFZhbHVlSAASFgoMbnVtYmVyX3ZhbHVlGAIgASgBSAASFgoMc3RyaW5nX3ZhbHVlGAMgASgJSAASFAoKYm9vbF92YWx1ZRgEIAEoCEgAEi8KDHN0cnVjdF92YWx1ZRgFIAEoCzIXLmdvb2dsZS5wcm90b2J1Zi5TdHJ1Y3RIABIwCgpsaXN0X3ZhbHVlGAYgASgLMhouZ29vZ2xlLnByb3RvYnVmLkxpc3RWYWx1ZUgAQgYKBGtpbmQiMwoJTGlzdFZhbHVlEiYKBnZhbHVlcxgBIAMoCzIWLmdvb2dsZS5wcm90b2J1Zi5WYWx1ZSobCglOdWxsVmFsdWUSDgoKTlVMTF9WQUxVRRAAQn8KE2NvbS5nb29nbGUucHJvdG9idWZCC1N0cnVjdFByb3RvUAFaL2dvb2dsZS5nb2xhbmcub3JnL3Byb3RvYnVmL3R5cGVzL2tub3duL3N0cnVjdHBi+AEBogIDR1BCqgIeR29vZ2xlLlByb3RvYnVmLldlbGxLbm93blR5cGVzYgZwcm90bzM`),Zr=R(Xr,0),Qr=R(Xr,1),$r=R(Xr,2),ei;(function(e){e[e.NULL_VALUE=0]=`NULL_VALUE`})(ei||={});function ti(e,t,n){ai(t,e);let r=ri(e.$unknown,t),[i,a,o]=ii(t),s=or(n);for(let e of r)pr(i,new Ne(e.data),a,e.wireType,s);return o()}function ni(e,t,n){ai(t,e);let r=(e.$unknown??[]).filter(e=>e.no!==t.number),[i,a]=ii(t,n),o=new Ee;Hr(o,{writeUnknownFields:!0},i,a);let s=new Ne(o.finish());for(;s.pos<s.len;){let[e,t]=s.tag(),n=s.skip(t,e);r.push({no:e,wireType:t,data:n})}e.$unknown=r}function ri(e,t){if(e===void 0)return[];if(t.fieldKind===`enum`||t.fieldKind===`scalar`){for(let n=e.length-1;n>=0;--n)if(e[n].no==t.number)return[e[n]];return[]}return e.filter(e=>e.no===t.number)}function ii(e,t){let n=e.typeName,r=Object.assign(Object.assign({},e),{kind:`field`,parent:e.extendee,localName:n}),i=Object.assign(Object.assign({},e.extendee),{fields:[r],members:[r],oneofs:[]}),a=N(i,t===void 0?void 0:{[n]:t});return[et(i,a),r,()=>{let t=a[n];if(t===void 0){let t=e.message;return M(t)?_(t.fields[0].scalar,t.fields[0].longAsString):N(t)}return t}]}function ai(e,t){if(e.extendee.typeName!=t.$typeName)throw Error(`extension ${e.typeName} can only be applied to message ${e.extendee.typeName}`)}var oi=Date.parse(`0001-01-01T00:00:00Z`),si=Date.parse(`9999-12-31T23:59:59Z`),ci=3,li=2,ui={alwaysEmitImplicit:!1,enumAsInteger:!1,useProtoFieldName:!1};function di(e){return e?Object.assign(Object.assign({},ui),e):ui}function fi(e,t,n){return hi(e)(di(n),t)}function pi(e,t,n){let r=fi(e,t,n);return JSON.stringify(r,null,n?.prettySpaces??0)}var mi=new WeakMap;function hi(e){let t=mi.get(e);return t===void 0&&(t=gi(e)),t}function gi(e){let t=e.typeName,n=vi(e);if(n!==void 0){let r=e.fields[0],i=(e,i)=>{if(i.$typeName!==t&&r!==void 0)throw new F(r,`cannot use ${r} with message ${i.$typeName}`,`ForeignFieldError`);return n(e,i)};return mi.set(e,i),i}let r=e.fields.concat().sort((e,t)=>e.number-t.number),i=r[0],a=[],o=(n,r)=>{if(r.$typeName!==t&&i!==void 0)throw new F(i,`cannot use ${i} with message ${r.$typeName}`,`ForeignFieldError`);let o={};for(let e=0;e<a.length;e++)a[e](n,r,o);return n.registry&&Mi(o,n,n.registry,r,e),o};mi.set(e,o);for(let e of r){let t=yi(e);a.push(e.jsonName===`__proto__`||e.name===`__proto__`?_i(t):t)}return o}function _i(e){return(t,n,r)=>{let i=Object.create(null);e(t,n,i);for(let e of Object.keys(i))E(r,e,i[e])}}function vi(e){if(e.typeName.startsWith(`google.protobuf.`))switch(e.typeName){case`google.protobuf.Any`:return(e,t)=>Ni(t,e);case`google.protobuf.Timestamp`:return(e,t)=>zi(t);case`google.protobuf.Duration`:return(e,t)=>Pi(t);case`google.protobuf.FieldMask`:return(e,t)=>Fi(t);case`google.protobuf.Struct`:return(e,t)=>Ii(t);case`google.protobuf.Value`:return(e,t)=>Li(t);case`google.protobuf.ListValue`:return(e,t)=>Ri(t);default:if(M(e)){let t=e.fields[0],n=t.localName,r=_(t.scalar,!1),i=Ai(t);return(e,t)=>{let a=t[n];return i(e,a===void 0?r:a)}}return}}function yi(e){switch(e.fieldKind){case`scalar`:case`enum`:case`message`:return bi(e);case`list`:case`map`:{let t=e.fieldKind==`list`?wi(e):Ei(e),n=e.name,r=e.jsonName,i=e.localName;return(e,a,o)=>{let s=t(e,a[i]);s!==void 0&&(o[e.useProtoFieldName?n:r]=s)}}}}function bi(e){let n=Si(e),r=e.name,i=e.jsonName,a=e.localName;if(e.oneof){let t=e.oneof.localName;return(e,o,s)=>{let c=o[t];c.case===a&&(s[e.useProtoFieldName?r:i]=n(e,c.value))}}if(e.presence!=li){let t=e.presence==ci?`cannot encode ${e} to JSON: required field not set`:void 0;return(e,o,s)=>{let c=o[a];if(c!==void 0&&Object.prototype.hasOwnProperty.call(o,a))s[e.useProtoFieldName?r:i]=n(e,c);else if(t!==void 0)throw Error(t)}}if(e.fieldKind==`enum`){let t=e.enum.values[0].number;return(e,o,s)=>{let c=o[a];(c!==t||e.alwaysEmitImplicit)&&(s[e.useProtoFieldName?r:i]=n(e,c))}}switch(e.scalar){case t.BOOL:return(e,t,o)=>{let s=t[a];(s!==!1||e.alwaysEmitImplicit)&&(o[e.useProtoFieldName?r:i]=n(e,s))};case t.STRING:return(e,t,o)=>{let s=t[a];(s!==``||e.alwaysEmitImplicit)&&(o[e.useProtoFieldName?r:i]=n(e,s))};case t.BYTES:return(e,t,o)=>{let s=t[a];(!(s instanceof Uint8Array)||s.byteLength>0||e.alwaysEmitImplicit)&&(o[e.useProtoFieldName?r:i]=n(e,s))};case t.DOUBLE:case t.FLOAT:return(e,t,o)=>{let s=t[a];(!Object.is(s,0)||e.alwaysEmitImplicit)&&(o[e.useProtoFieldName?r:i]=n(e,s))};default:return(e,t,o)=>{let s=t[a];(s!=0||e.alwaysEmitImplicit)&&(o[e.useProtoFieldName?r:i]=n(e,s))}}}function xi(e){switch(e.fieldKind){case`scalar`:case`enum`:case`message`:return Si(e);case`list`:return wi(e);case`map`:return Ei(e)}}function Si(e){switch(e.fieldKind){case`scalar`:return Ai(e);case`enum`:return Oi(e);case`message`:return Ci(e)}}function Ci(e){let{toMessage:t}=Je(e),n=hi(e.message);return(e,r)=>n(e,t(r))}function wi(e){let t=Ti(e);return(e,n)=>{let r=n;if(r.length==0&&!e.alwaysEmitImplicit)return;let i=[];for(let n=0;n<r.length;n++)i.push(t(e,r[n]));return i}}function Ti(e){switch(e.listKind){case`scalar`:return Ai(e);case`enum`:return Oi(e);case`message`:return Ci(e)}}function Ei(e){let t=Di(e);return(e,n)=>{let r=n,i=Object.keys(r);if(i.length==0&&!e.alwaysEmitImplicit)return;let a={};for(let n=0;n<i.length;n++){let o=i[n];E(a,o,t(e,r[o]))}return a}}function Di(e){switch(e.mapKind){case`scalar`:return Ai(e);case`enum`:return Oi(e);case`message`:return Ci(e)}}function Oi(e){let t=e.enum;return t.typeName==`google.protobuf.NullValue`?(e,n)=>{if(typeof n!=`number`)throw ki(t,n);return null}:(e,n)=>{if(typeof n!=`number`)throw ki(t,n);return e.enumAsInteger?n:t.value[n]?.jsonName??n}}function ki(e,t){return Error(`cannot encode ${e} to JSON: expected number, got ${L(t)}`)}function Ai(e){switch(e.scalar){case t.INT32:case t.SFIXED32:case t.SINT32:case t.FIXED32:case t.UINT32:return(t,n)=>{if(typeof n!=`number`)throw ji(e,n);return n};case t.FLOAT:case t.DOUBLE:return(t,n)=>{if(typeof n!=`number`)throw ji(e,n);return Number.isNaN(n)?`NaN`:n===1/0?`Infinity`:n===-1/0?`-Infinity`:n};case t.STRING:return(t,n)=>{if(typeof n!=`string`)throw ji(e,n);return n};case t.BOOL:return(t,n)=>{if(typeof n!=`boolean`)throw ji(e,n);return n};case t.UINT64:case t.FIXED64:case t.INT64:case t.SFIXED64:case t.SINT64:return(t,n)=>{if(typeof n==`bigint`||typeof n==`string`||typeof n==`number`&&Number.isInteger(n))return n.toString();throw ji(e,n)};case t.BYTES:return(t,n)=>{if(n instanceof Uint8Array)return xt(n);throw ji(e,n)}}}function ji(e,t){return Error(`cannot encode ${e} to JSON: ${Le(e,t)?.message}`)}function Mi(e,t,n,r,i){let a=r.$unknown;if(a===void 0)return;let o=new Set;for(let s=0;s<a.length;s++){let{no:c}=a[s];if(!o.has(c)){o.add(c);let a=n.getExtensionFor(i,c);if(!a)continue;let[s,l]=ii(a,ti(r,a)),u=s[b],d=xi(l)(t,u[l.localName]);d!==void 0&&(e[a.jsonName]=d)}}}function Ni(e,t){if(e.typeUrl===``)return{};let{registry:n}=t,r,i;if(n&&(r=qr(e,n),r&&(i=n.getMessage(r.$typeName))),!i||!r)throw Error(`cannot encode message ${e.$typeName} to JSON: "${e.typeUrl}" is not in the type registry`);let a=ne(i)?{value:hi(i)(t,r)}:hi(i)(t,r);return a[`@type`]=e.typeUrl,a}function Pi(e){let t=Number(e.seconds),n=e.nanos;if(t>315576e6||t<-315576e6)throw Error(`cannot encode message ${e.$typeName} to JSON: value out of range`);if(t>0&&n<0||t<0&&n>0)throw Error(`cannot encode message ${e.$typeName} to JSON: nanos sign must match seconds sign`);let r=e.seconds.toString();if(n!==0){let e=Math.abs(n).toString();e=`0`.repeat(9-e.length)+e,e.substring(3)===`000000`?e=e.substring(0,3):e.substring(6)===`000`&&(e=e.substring(0,6)),r+=`.`+e,n<0&&t==0&&(r=`-`+r)}return r+`s`}function Fi(e){return e.paths.map(t=>{if(Ot(Dt(t))!==t)throw Error(`cannot encode message ${e.$typeName} to JSON: lowerCamelCase of path name "${t}" is irreversible`);return Dt(t)}).join(`,`)}function Ii(e){let t={},n=Object.keys(e.fields);for(let r=0;r<n.length;r++){let i=n[r];E(t,i,Li(e.fields[i]))}return t}function Li(e){switch(e.kind.case){case`nullValue`:return null;case`numberValue`:if(!Number.isFinite(e.kind.value))throw Error(`${e.$typeName} cannot be NaN or Infinity`);return e.kind.value;case`boolValue`:case`stringValue`:return e.kind.value;case`structValue`:return Ii(e.kind.value);case`listValue`:return Ri(e.kind.value);default:throw Error(`${e.$typeName} must have a value`)}}function Ri(e){return e.values.map(Li)}function zi(e){let t=Number(e.seconds)*1e3;if(t<oi||t>si)throw Error(`cannot encode message ${e.$typeName} to JSON: must be from 0001-01-01T00:00:00Z to 9999-12-31T23:59:59Z inclusive`);if(e.nanos<0)throw Error(`cannot encode message ${e.$typeName} to JSON: nanos must not be negative`);if(e.nanos>999999999)throw Error(`cannot encode message ${e.$typeName} to JSON: nanos must not be greater than 999999999`);let n=`Z`;if(e.nanos>0){let t=(e.nanos+1e9).toString().substring(1);n=t.substring(3)===`000000`?`.`+t.substring(0,3)+`Z`:t.substring(6)===`000`?`.`+t.substring(0,6)+`Z`:`.`+t+`Z`}return new Date(t).toISOString().replace(`.000Z`,n)}var Bi=2;function Vi(e){return Object.assign(Object.assign({ignoreUnknownFields:!1,recursionLimit:100},e),{depth:0})}function Hi(e,t,n){return Ui(e,da(t,e.typeName),n)}function Ui(e,t,n){let r=N(e);return Wi(e,r,t,n),r}function Wi(e,t,n,r){try{Ki(e)(t,n,Vi(r))}catch(e){throw xe(e)?Error(`cannot decode ${e.field()} from JSON: ${e.message}`,{cause:e}):e}}var Gi=new WeakMap;function Ki(e){let t=Gi.get(e);return t===void 0&&(t=qi(e)),t}function qi(e){let t=String(e),n=Ji(e);if(n!==void 0){let r=(e,r,i)=>{if(++i.depth>i.recursionLimit)throw Error(`cannot decode ${t} from JSON: maximum recursion depth of ${i.recursionLimit} reached`);n(e,r,i),i.depth--};return Gi.set(e,r),r}let r=e.typeName,i=new Map,a=(e,n,a)=>{if(++a.depth>a.recursionLimit)throw Error(`cannot decode ${t} from JSON: maximum recursion depth of ${a.recursionLimit} reached`);if(n==null||Array.isArray(n)||typeof n!=`object`)throw Error(`cannot decode ${t} from JSON: ${L(n)}`);let o=new Map,s=new Set,c=Object.keys(n);for(let l=0;l<c.length;l++){let u=c[l],d=n[u],f=i.get(u);if(f!==void 0){let t=f.field;if(s.has(t))throw new F(t,`set multiple times`);if(s.add(t),f.oneofScalarNullSkip&&d===null)continue;if(f.oneof){let e=o.get(f.oneof);if(e!==void 0)throw new F(f.oneof,`oneof set multiple times by ${e.name} and ${t.name}`);o.set(f.oneof,t)}f.read(e,d,a)}else{let n=u.startsWith(`[`)&&u.endsWith(`]`)?a.registry?.getExtension(u.substring(1,u.length-1)):void 0;if(n?.extendee.typeName==r){let[t,r,i]=ii(n);Yi(r)(t[b],d,a),ni(e,n,i())}if(n===void 0&&!a.ignoreUnknownFields)throw Error(`cannot decode ${t} from JSON: key "${u}" is unknown`)}}a.depth--};Gi.set(e,a);for(let t of e.fields){let e={read:Yi(t),field:t,oneof:t.oneof,oneofScalarNullSkip:t.oneof!==void 0&&t.fieldKind==`scalar`};i.set(t.name,e).set(t.jsonName,e)}return a}function Ji(e){if(e.typeName.startsWith(`google.protobuf.`))switch(e.typeName){case`google.protobuf.Any`:return(e,t,n)=>pa(e,t,n);case`google.protobuf.Timestamp`:return(e,t)=>ma(e,t);case`google.protobuf.Duration`:return(e,t)=>ha(e,t);case`google.protobuf.FieldMask`:return(e,t)=>ga(e,t);case`google.protobuf.Struct`:return(e,t,n)=>_a(e,t,n);case`google.protobuf.Value`:return(e,t,n)=>va(e,t,n);case`google.protobuf.ListValue`:return(e,t,n)=>ya(e,t,n);default:if(M(e)){let t=e.fields[0],n=t.localName,r=t.scalar,i=t.longAsString,a=oa(t);return(e,t)=>{t===null?e[n]=_(r,i):e[n]=a(t)}}return}}function Yi(e){switch(e.fieldKind){case`scalar`:return Xi(e);case`enum`:return Qi(e);case`message`:return $i(e);case`list`:return ea(e);case`map`:return na(e)}}function Xi(e){let t=oa(e),n=e.localName;if(e.oneof){let r=e.oneof.localName;return(e,i)=>{e[r]={case:n,value:t(i)}}}let r=Zi(e);return(e,i)=>{i===null?r(e):e[n]=t(i)}}function Zi(e){let t=e.localName;if(e.presence!=Bi)return e=>{delete e[t]};if(e.fieldKind==`enum`){let n=e.enum.values[0].number;return e=>{e[t]=n}}let n=e.scalar,r=e.longAsString;return e=>{e[t]=_(n,r)}}function Qi(e){let t=ia(e.enum),n=aa(e.enum),r=e.localName,i=e.enum.typeName!=`google.protobuf.NullValue`;if(e.oneof){let a=e.oneof.localName;return(o,s,c)=>{if(s===null&&i){o[a].case===r&&(o[a]={case:void 0});return}let l=t(s,c.ignoreUnknownFields);if(l===ra)return;let u=n(l);if(u!==!0)throw new F(e,He(e,l,u));o[a]={case:r,value:l}}}let a=Zi(e);return(o,s,c)=>{if(s===null&&i){a(o);return}let l=t(s,c.ignoreUnknownFields);if(l===ra)return;let u=n(l);if(u!==!0)throw new F(e,He(e,l,u));o[r]=l}}function $i(e){let t=e.localName,{toMessage:n,toLocal:r}=Je(e),i=Ki(e.message),a=e.message.typeName!=`google.protobuf.Value`;if(e.oneof){let o=e.oneof.localName;return(e,s,c)=>{let l=e[o];if(s===null&&a){l.case===t&&(e[o]={case:void 0});return}let u=n(l.case===t?l.value:void 0);i(u,s,c),e[o]={case:t,value:r(u)}}}return(e,o,s)=>{if(o===null&&a){delete e[t];return}let c=n(e[t]);i(c,o,s),e[t]=r(c)}}function ea(e){let t=e.localName,n=ta(e);return(r,i,a)=>{if(i===null)return;if(!Array.isArray(i))throw new F(e,`expected Array, got `+L(i));let o=r[t];for(let e=0;e<i.length;e++){let t=n(i[e],a,o.length);t!==ra&&o.push(t)}}}function ta(e){switch(e.listKind){case`scalar`:{let t=sa(e),n=Ve(e.scalar),r=ca(e);return(i,a,o)=>{if(i===null)throw new F(e,`list item must not be null`);let s=t(i),c=n(s);if(c!==!0)throw new F(e,`list item #${o+1}: ${He(e,s,c)}`);return r(s)}}case`enum`:{let t=ia(e.enum),n=aa(e.enum),r=e.enum.typeName!=`google.protobuf.NullValue`;return(i,a,o)=>{if(i===null&&r)throw new F(e,`list item must not be null`);let s=t(i,a.ignoreUnknownFields);if(s===ra)return s;let c=n(s);if(c!==!0)throw new F(e,`list item #${o+1}: ${He(e,s,c)}`);return s}}case`message`:{let{toMessage:t,toLocal:n}=Je(e),r=Ki(e.message),i=e.message.typeName!=`google.protobuf.Value`;return(a,o)=>{if(a===null&&i)throw new F(e,`list item must not be null`);let s=t(void 0);return r(s,a,o),n(s)}}}}function na(e){let t=e.localName,n=e.mapKey,r=la(n),i=Ve(n),a,o,s=e=>e,c=!0;switch(e.mapKind){case`scalar`:a=sa(e),o=Ve(e.scalar),s=ca(e);break;case`enum`:{let t=ia(e.enum);a=(e,n)=>t(e,n.ignoreUnknownFields),o=aa(e.enum),c=e.enum.typeName!=`google.protobuf.NullValue`;break}case`message`:{let{toMessage:t,toLocal:n}=Je(e),r=Ki(e.message);c=e.message.typeName!=`google.protobuf.Value`,a=(e,i)=>{let a=t(void 0);return r(a,e,i),n(a)};break}}return(l,u,d)=>{if(u===null)return;if(typeof u!=`object`||Array.isArray(u))throw new F(e,`expected object, got `+L(u));let f=l[t],p=new Set,m=Object.keys(u);for(let t=0;t<m.length;t++){let l=m[t],h=u[l],g=r(l);if(p.has(g))throw new F(e,`duplicate map key "${l}"`);if(p.add(g),h===null&&c)throw new F(e,`map value must not be null`);let _=a(h,d);if(_===ra)continue;let v=i(g);if(v!==!0)throw new F(e,`invalid map key: ${He({scalar:n},g,v)}`);if(o!==void 0){let t=o(_);if(t!==!0)throw new F(e,`map entry ${L(g)}: ${He(e,_,t)}`)}E(f,g,s(_))}}}var ra=Symbol();function ia(e){let t=e.values[0].number,n=new Map;for(let t of e.values)n.set(t.jsonName,t.number);for(let t of e.values)n.set(t.name,t.number);return(r,i)=>{if(r===null)return t;switch(typeof r){case`number`:if(Number.isInteger(r))return r;break;case`string`:{let e=n.get(r);if(e!==void 0)return e;if(i)return ra;break}}throw Error(`cannot decode ${e} from JSON: ${L(r)}`)}}function aa(e){if(e.open)return Ve(t.INT32);let n=e.values;return e=>n.some(t=>t.number===e)}function oa(e){let t=sa(e),n=Ve(e.scalar),r=ca(e);return i=>{let a=t(i),o=n(a);if(o!==!0)throw new F(e,He(e,a,o));return r(a)}}function sa(e){switch(e.scalar){case t.DOUBLE:case t.FLOAT:return t=>{if(t===`NaN`)return NaN;if(t===`Infinity`)return 1/0;if(t===`-Infinity`)return-1/0;if(typeof t==`number`){if(Number.isNaN(t))throw new F(e,`unexpected NaN number`);if(!Number.isFinite(t))throw new F(e,`unexpected infinite number`);return t}if(typeof t==`string`){if(t===``||t.trim().length!==t.length)return t;let e=Number(t);return Number.isFinite(e)?e:t}return t};case t.INT32:case t.FIXED32:case t.SFIXED32:case t.SINT32:case t.UINT32:return ua;case t.BYTES:return t=>{if(typeof t==`string`){if(t===``)return new Uint8Array;try{return _t(t)}catch(t){throw new F(e,t instanceof Error?t.message:String(t))}}return t};default:return e=>e}}function ca(e){let n=e.fieldKind!==`map`&&e.longAsString;switch(e.scalar){case t.INT64:case t.SFIXED64:case t.SINT64:return n?e=>String(e):e=>typeof e==`string`||typeof e==`number`?p.parse(e):e;case t.FIXED64:case t.UINT64:return n?e=>String(e):e=>typeof e==`string`||typeof e==`number`?p.uParse(e):e;default:return e=>e}}function la(e){switch(e){case t.BOOL:return e=>{switch(e){case`true`:return!0;case`false`:return!1}return e};case t.INT32:case t.FIXED32:case t.UINT32:case t.SFIXED32:case t.SINT32:return ua;case t.INT64:case t.SINT64:case t.SFIXED64:case t.UINT64:case t.FIXED64:return e=>/^-?0+$/.test(e)?`0`:e.replace(/^(-?)0+(?=\d)/,`$1`);default:return e=>e}}function ua(e){if(typeof e==`string`){if(e===``||e.trim().length!==e.length)return e;let t=Number(e);return Number.isNaN(t)?e:t}return e}function da(e,t){let n;try{n=JSON.parse(e)}catch(e){let n=e instanceof Error?e.message:String(e);throw Error(`cannot decode message ${t} from JSON: ${n}`,{cause:e})}return fa(e,t),n}function fa(e,t){let n=[],r=!1,i=0;for(;i<e.length;)switch(e[i]){case`{`:n.push(new Set),r=!0,i++;break;case`[`:n.push(null),r=!1,i++;break;case`}`:case`]`:n.pop(),r=!1,i++;break;case`,`:r=n[n.length-1]!=null,i++;break;case`:`:r=!1,i++;break;case`"`:{let a=i++,o=!1;for(;i<e.length;)if(e[i]==`\\`)o=!0,i+=2;else{if(e[i]==`"`)break;i++}let s=i++,c=n[n.length-1];if(r&&c){let n=o?JSON.parse(e.substring(a,s+1)):e.substring(a+1,s);if(c.has(n))throw Error(`cannot decode message ${t} from JSON: duplicate object key "${n}"`);c.add(n)}r=!1;break}default:i++}}function pa(e,t,n){if(t===null||Array.isArray(t)||typeof t!=`object`)throw Error(`cannot decode message ${e.$typeName} from JSON: expected object but got ${L(t)}`);if(Object.keys(t).length==0)return;let r=t[`@type`];if(typeof r!=`string`||r==``)throw Error(`cannot decode message ${e.$typeName} from JSON: "@type" is empty`);let i=r.includes(`/`)?r.substring(r.lastIndexOf(`/`)+1):r;if(!i.length)throw Error(`cannot decode message ${e.$typeName} from JSON: "@type" is invalid`);let a=n.registry?.getMessage(i);if(!a)throw Error(`cannot decode message ${e.$typeName} from JSON: ${r} is not in the type registry`);let o=N(a);if(ne(a)&&Object.prototype.hasOwnProperty.call(t,`value`))Ki(a)(o,t.value,n);else{let e={};for(let n of Object.keys(t))n!==`@type`&&E(e,n,t[n]);Ki(a)(o,e,n)}Gr(a,o,e)}function ma(e,t){if(typeof t!=`string`)throw Error(`cannot decode message ${e.$typeName} from JSON: ${L(t)}`);let n=t.match(/^([0-9]{4})-([0-9]{2})-([0-9]{2})T([0-9]{2}):([0-9]{2}):([0-9]{2})(?:\.([0-9]{1,9}))?(?:Z|([+-][0-9][0-9]:[0-9][0-9]))$/);if(!n)throw Error(`cannot decode message ${e.$typeName} from JSON: invalid RFC 3339 string`);let r=Date.parse(n[1]+`-`+n[2]+`-`+n[3]+`T`+n[4]+`:`+n[5]+`:`+n[6]+(n[8]?n[8]:`Z`));if(Number.isNaN(r))throw Error(`cannot decode message ${e.$typeName} from JSON: invalid RFC 3339 string`);if(r<oi||r>si)throw Error(`cannot decode message ${e.$typeName} from JSON: must be from 0001-01-01T00:00:00Z to 9999-12-31T23:59:59Z inclusive`);e.seconds=p.parse(r/1e3),e.nanos=0,n[7]&&(e.nanos=parseInt(`1`+n[7]+`0`.repeat(9-n[7].length))-1e9)}function ha(e,t){if(typeof t!=`string`)throw Error(`cannot decode message ${e.$typeName} from JSON: ${L(t)}`);let n=t.match(/^(-?[0-9]+)(?:\.([0-9]+))?s/);if(n===null)throw Error(`cannot decode message ${e.$typeName} from JSON: ${L(t)}`);let r=Number(n[1]);if(r>315576e6||r<-315576e6)throw Error(`cannot decode message ${e.$typeName} from JSON: ${L(t)}`);if(e.seconds=p.parse(r),typeof n[2]!=`string`)return;let i=n[2]+`0`.repeat(9-n[2].length);e.nanos=parseInt(i),(r<0||Object.is(r,-0))&&(e.nanos=-e.nanos)}function ga(e,t){if(typeof t!=`string`)throw Error(`cannot decode message ${e.$typeName} from JSON: ${L(t)}`);t!==``&&(e.paths=t.split(`,`).map(t=>{if(t.includes(`_`))throw Error(`cannot decode message ${e.$typeName} from JSON: path names must be lowerCamelCase`);return Ot(t)}))}function _a(e,t,n){if(typeof t!=`object`||!t||Array.isArray(t))throw Error(`cannot decode message ${e.$typeName} from JSON ${L(t)}`);let r=Object.keys(t);for(let i=0;i<r.length;i++){let a=r[i],o=N(Qr);va(o,t[a],n),E(e.fields,a,o)}}function va(e,t,n){if(++n.depth>n.recursionLimit)throw Error(`cannot decode ${e.$typeName} from JSON: maximum recursion depth of ${n.recursionLimit} reached`);switch(typeof t){case`number`:e.kind={case:`numberValue`,value:t};break;case`string`:e.kind={case:`stringValue`,value:t};break;case`boolean`:e.kind={case:`boolValue`,value:t};break;case`object`:if(t===null)e.kind={case:`nullValue`,value:ei.NULL_VALUE};else if(Array.isArray(t)){let r=N($r);ya(r,t,n),e.kind={case:`listValue`,value:r}}else{let r=N(Zr);_a(r,t,n),e.kind={case:`structValue`,value:r}}break;default:throw Error(`cannot decode message ${e.$typeName} from JSON ${L(t)}`)}return n.depth--,e}function ya(e,t,n){if(!Array.isArray(t))throw Error(`cannot decode message ${e.$typeName} from JSON ${L(t)}`);for(let r=0;r<t.length;r++){let i=N(Qr);va(i,t[r],n),e.values.push(i)}}var z;(function(e){e[e.Canceled=1]=`Canceled`,e[e.Unknown=2]=`Unknown`,e[e.InvalidArgument=3]=`InvalidArgument`,e[e.DeadlineExceeded=4]=`DeadlineExceeded`,e[e.NotFound=5]=`NotFound`,e[e.AlreadyExists=6]=`AlreadyExists`,e[e.PermissionDenied=7]=`PermissionDenied`,e[e.ResourceExhausted=8]=`ResourceExhausted`,e[e.FailedPrecondition=9]=`FailedPrecondition`,e[e.Aborted=10]=`Aborted`,e[e.OutOfRange=11]=`OutOfRange`,e[e.Unimplemented=12]=`Unimplemented`,e[e.Internal=13]=`Internal`,e[e.Unavailable=14]=`Unavailable`,e[e.DataLoss=15]=`DataLoss`,e[e.Unauthenticated=16]=`Unauthenticated`})(z||={});function ba(e){let t=z[e];return typeof t==`string`?t[0].toLowerCase()+t.substring(1).replace(/[A-Z]/g,e=>`_`+e.toLowerCase()):e.toString()}var B=class e extends Error{constructor(e,t=z.Unknown,n,r,i){super(xa(e,t)),this.name=`ConnectError`,this.isWireError=!1,Object.setPrototypeOf(this,new.target.prototype),this.rawMessage=e,this.code=t,this.metadata=new Headers(n??{}),this.details=r??[],this.cause=i}static from(t,n=z.Unknown){return t instanceof e?t:t instanceof Error?t.name==`AbortError`||t.name==`TimeoutError`?new e(t.message,z.Canceled):new e(t.message,n,void 0,void 0,t):new e(String(t),n,void 0,void 0,t)}static[Symbol.hasInstance](t){return t instanceof Error?Object.getPrototypeOf(t)===e.prototype||t.name===`ConnectError`&&`code`in t&&typeof t.code==`number`&&`metadata`in t&&`details`in t&&Array.isArray(t.details)&&`rawMessage`in t&&typeof t.rawMessage==`string`&&`cause`in t:!1}findDetails(e){let t=e.kind===`message`?{getMessage:t=>t===e.typeName?e:void 0}:e,n=[];for(let e of this.details){if(`desc`in e){t.getMessage(e.desc.typeName)&&n.push(N(e.desc,e.value));continue}let r=t.getMessage(e.type);if(r)try{n.push(sr(r,e.value))}catch{}}return n}};function xa(e,t){return e.length?`[${ba(t)}] ${e}`:`[${ba(t)}]`}function Sa(e,t,n){try{let r=_t(e);return t?sr(t,r,n):r}catch(e){throw B.from(e,z.DataLoss)}}function Ca(e,t){let n={};for(let r of e.methods){let e=t(r);e!=null&&(n[r.localName]=e)}return n}function wa(e,t,n=!1){if(t>e){let r=`message size is larger than configured readMaxBytes ${e}`;throw n&&(r=`message size ${t} is larger than configured readMaxBytes ${e}`),new B(r,z.ResourceExhausted)}}function Ta(e){return new Ea(e)}var Ea=class{constructor(e){this.readMaxBytes=e,this.header=new Uint8Array(5),this.headerView=new DataView(this.header.buffer),this.buf=[]}get byteLength(){return this.buf.reduce((e,t)=>e+t.byteLength,0)}decode(e){this.buf.push(e);let t=[];for(;;){let e=this.pop();if(!e)break;t.push(e)}return t}pop(){if(!(!this.env&&(this.env=this.head(),!this.env))&&this.cons(this.env.data)){let e=this.env;return this.env=void 0,e}}head(){if(!this.cons(this.header))return;let e=this.headerView.getUint8(0),t=this.headerView.getUint32(1);return wa(this.readMaxBytes,t,!0),{flags:e,data:new Uint8Array(t)}}cons(e){let t=e.byteLength;if(this.byteLength<t)return!1;let n=0;for(;n<t;){let r=this.buf.shift();r.byteLength>t-n?(e.set(r.subarray(0,t-n),n),this.buf.unshift(r.subarray(t-n)),n+=t-n):(e.set(r,n),n+=r.byteLength)}return!0}};function Da(e){let t,n=Ta(0xffffffff);return new ReadableStream({start(){t=e.getReader()},async pull(e){let r=!1;for(;!r;){let i=await t.read();if(i.done)n.byteLength>0&&e.error(new B(`protocol error: incomplete envelope`,z.InvalidArgument)),e.close();else for(let t of n.decode(i.value))e.enqueue(t),r=!0}}})}function Oa(e,t){let n=new Uint8Array(t.length+5);n.set(t,5);let r=new DataView(n.buffer,n.byteOffset,n.byteLength);return r.setUint8(0,e),r.setUint32(1,t.length),n}var ka=function(e){if(!Symbol.asyncIterator)throw TypeError(`Symbol.asyncIterator is not defined.`);var t=e[Symbol.asyncIterator],n;return t?t.call(e):(e=typeof __values==`function`?__values(e):e[Symbol.iterator](),n={},r(`next`),r(`throw`),r(`return`),n[Symbol.asyncIterator]=function(){return this},n);function r(t){n[t]=e[t]&&function(n){return new Promise(function(r,a){n=e[t](n),i(r,a,n.done,n.value)})}}function i(e,t,n,r){Promise.resolve(r).then(function(t){e({value:t,done:n})},t)}},Aa=function(e){return this instanceof Aa?(this.v=e,this):new Aa(e)},ja=function(e,t,n){if(!Symbol.asyncIterator)throw TypeError(`Symbol.asyncIterator is not defined.`);var r=n.apply(e,t||[]),i,a=[];return i=Object.create((typeof AsyncIterator==`function`?AsyncIterator:Object).prototype),s(`next`),s(`throw`),s(`return`,o),i[Symbol.asyncIterator]=function(){return this},i;function o(e){return function(t){return Promise.resolve(t).then(e,d)}}function s(e,t){r[e]&&(i[e]=function(t){return new Promise(function(n,r){a.push([e,t,n,r])>1||c(e,t)})},t&&(i[e]=t(i[e])))}function c(e,t){try{l(r[e](t))}catch(e){f(a[0][3],e)}}function l(e){e.value instanceof Aa?Promise.resolve(e.value.v).then(u,d):f(a[0][2],e)}function u(e){c(`next`,e)}function d(e){c(`throw`,e)}function f(e,t){e(t),a.shift(),a.length&&c(a[0][0],a[0][1])}},Ma=function(e){var t={},n;return r(`next`),r(`throw`,function(e){throw e}),r(`return`),t[Symbol.iterator]=function(){return this},t;function r(r,i){t[r]=e[r]?function(t){return(n=!n)?{value:Aa(e[r](t)),done:!1}:i?i(t):t}:i}};function Na(e){return ja(this,arguments,function*(){yield Aa(yield*Ma(ka(e)))})}var Pa=function(e){if(!Symbol.asyncIterator)throw TypeError(`Symbol.asyncIterator is not defined.`);var t=e[Symbol.asyncIterator],n;return t?t.call(e):(e=typeof __values==`function`?__values(e):e[Symbol.iterator](),n={},r(`next`),r(`throw`),r(`return`),n[Symbol.asyncIterator]=function(){return this},n);function r(t){n[t]=e[t]&&function(n){return new Promise(function(r,a){n=e[t](n),i(r,a,n.done,n.value)})}}function i(e,t,n,r){Promise.resolve(r).then(function(t){e({value:t,done:n})},t)}},Fa=function(e){return this instanceof Fa?(this.v=e,this):new Fa(e)},Ia=function(e){var t={},n;return r(`next`),r(`throw`,function(e){throw e}),r(`return`),t[Symbol.iterator]=function(){return this},t;function r(r,i){t[r]=e[r]?function(t){return(n=!n)?{value:Fa(e[r](t)),done:!1}:i?i(t):t}:i}},La=function(e,t,n){if(!Symbol.asyncIterator)throw TypeError(`Symbol.asyncIterator is not defined.`);var r=n.apply(e,t||[]),i,a=[];return i=Object.create((typeof AsyncIterator==`function`?AsyncIterator:Object).prototype),s(`next`),s(`throw`),s(`return`,o),i[Symbol.asyncIterator]=function(){return this},i;function o(e){return function(t){return Promise.resolve(t).then(e,d)}}function s(e,t){r[e]&&(i[e]=function(t){return new Promise(function(n,r){a.push([e,t,n,r])>1||c(e,t)})},t&&(i[e]=t(i[e])))}function c(e,t){try{l(r[e](t))}catch(e){f(a[0][3],e)}}function l(e){e.value instanceof Fa?Promise.resolve(e.value.v).then(u,d):f(a[0][2],e)}function u(e){c(`next`,e)}function d(e){c(`throw`,e)}function f(e,t){e(t),a.shift(),a.length&&c(a[0][0],a[0][1])}};function Ra(e,t){return Ca(e,e=>{switch(e.methodKind){case`unary`:return za(t,e);case`server_streaming`:return Ba(t,e);case`client_streaming`:return Va(t,e);case`bidi_streaming`:return Ha(t,e);default:return null}})}function za(e,t){return async(n,r)=>{var i,a;let o=await e.unary(t,r?.signal,r?.timeoutMs,r?.headers,n,r?.contextValues);return(i=r?.onHeader)==null||i.call(r,o.header),(a=r?.onTrailer)==null||a.call(r,o.trailer),o.message}}function Ba(e,t){return(n,r)=>Ua(e.stream(t,r?.signal,r?.timeoutMs,r?.headers,Na([n]),r?.contextValues),r)}function Va(e,t){return async(n,r)=>{var i,a,o,s,c,l;let u=await e.stream(t,r?.signal,r?.timeoutMs,r?.headers,n,r?.contextValues);(c=r?.onHeader)==null||c.call(r,u.header);let d,f=0;try{for(var p=!0,m=Pa(u.message),h;h=await m.next(),i=h.done,!i;p=!0)s=h.value,p=!1,d=s,f++}catch(e){a={error:e}}finally{try{!p&&!i&&(o=m.return)&&await o.call(m)}finally{if(a)throw a.error}}if(!d)throw new B(`protocol error: missing response message`,z.Unimplemented);if(f>1)throw new B(`protocol error: received extra messages for client streaming method`,z.Unimplemented);return(l=r?.onTrailer)==null||l.call(r,u.trailer),d}}function Ha(e,t){return(n,r)=>Ua(e.stream(t,r?.signal,r?.timeoutMs,r?.headers,n,r?.contextValues),r)}function Ua(e,t){return(function(){return La(this,arguments,function*(){var n,r;let i=yield Fa(e);(n=t?.onHeader)==null||n.call(t,i.header),yield Fa(yield*Ia(Pa(i.message))),(r=t?.onTrailer)==null||r.call(t,i.trailer)})})()}function Wa(...e){let t=new AbortController,n=e.filter(e=>e!==void 0).concat(t.signal);for(let e of n){if(e.aborted){r.apply(e);break}e.addEventListener(`abort`,r)}function r(){t.signal.aborted||t.abort(Ka(this));for(let e of n)e.removeEventListener(`abort`,r)}return t}function Ga(e){let t=new AbortController,n=()=>{t.abort(new B(`the operation timed out`,z.DeadlineExceeded))},r;return e!==void 0&&(e<=0?n():r=setTimeout(n,e)),{signal:t.signal,cleanup:()=>clearTimeout(r)}}function Ka(e){if(!e.aborted)return;if(e.reason!==void 0)return e.reason;let t=Error(`This operation was aborted`);return t.name=`AbortError`,t}function qa(){return{get(e){return e.id in this?this[e.id]:e.defaultValue},set(e,t){return this[e.id]=t,this},delete(e){return delete this[e.id],this}}}function Ja(e){let t=new Headers,n=new TextDecoder().decode(e).split(`\r
`);for(let e of n){if(e===``)continue;let n=e.indexOf(`:`);if(n>0){let r=e.substring(0,n).trim(),i=e.substring(n+1).trim();t.append(r,i)}}return t}var Ya=`Content-Type`,Xa=`Grpc-Timeout`,Za=`Grpc-Status`,Qa=`Grpc-Status-Details-Bin`,$a=`User-Agent`,eo=`X-User-Agent`,to=`X-Grpc-Web`,no=`application/grpc-web+proto`,ro=`application/grpc-web+json`;function io(e,t,...n){if(n.length>0)throw Error();return e.services[t]}var ao=R(Sr(`CgxzdGF0dXMucHJvdG8SCmdvb2dsZS5ycGMiTgoGU3RhdHVzEgwKBGNvZGUYASABKAUSDwoHbWVzc2FnZRgCIAEoCRIlCgdkZXRhaWxzGAMgAygLMhQuZ29vZ2xlLnByb3RvYnVmLkFueUJeCg5jb20uZ29vZ2xlLnJwY0ILU3RhdHVzUHJvdG9QAVo3Z29vZ2xlLmdvbGFuZy5vcmcvZ2VucHJvdG8vZ29vZ2xlYXBpcy9ycGMvc3RhdHVzO3N0YXR1c6ICA1JQQ2IGcHJvdG8z`,[Cr]),0);function oo(e){let t=e.get(Qa);if(t!=null){let n=Sa(t,ao);if(n.code==0)return;let r=new B(n.message,n.code,e);return r.details=n.details.map(e=>({type:e.typeUrl.substring(e.typeUrl.lastIndexOf(`/`)+1),value:e.value})),r.isWireError=!0,r}let n=e.get(Za);if(n!=null){if(n===`0`)return;let t=parseInt(n,10),r;return r=t in z?new B(decodeURIComponent(e.get(`Grpc-Message`)??``),t,e):new B(`invalid grpc-status: ${n}`,z.Internal,e),r.isWireError=!0,r}}function so(e,t){return e.toString().replace(/\/?$/,`/${t.parent.typeName}/${t.name}`)}function co(e,t){return N(e,t)}function lo(e,t){function n(t){return t.done===!0?t:{done:t.done,value:co(e,t.value)}}return{[Symbol.asyncIterator](){let e=t[Symbol.asyncIterator](),r={next:()=>e.next().then(n)};return e.throw!==void 0&&(r.throw=t=>e.throw(t).then(n)),e.return!==void 0&&(r.return=t=>e.return(t).then(n)),r}}}function uo(e,t){if(!t)return e;for(let n of t.concat().reverse())e=n(e);return e}function fo(e){let t=Object.assign({},e);return t.ignoreUnknownFields??=!0,t}function po(e,t,n,r){let i=t?mo(e.input,r):ho(e.input,n);return{parse:(t?mo(e.output,r):ho(e.output,n)).parse,serialize:i.serialize}}function mo(e,t){return{parse(n){try{return sr(e,n,t)}catch(e){throw new B(`parse binary: ${e instanceof Error?e.message:String(e)}`,z.Internal)}},serialize(n){try{return kr(e,n,t)}catch(e){throw new B(`serialize binary: ${e instanceof Error?e.message:String(e)}`,z.Internal)}}}}function ho(e,t){let n=t?.textEncoder??new TextEncoder,r=t?.textDecoder??new TextDecoder,i=fo(t);return{parse(t){try{return Hi(e,r.decode(t),i)}catch(e){throw B.from(e,z.InvalidArgument)}},serialize(t){try{let r=pi(e,t,i);return n.encode(r)}catch(e){throw B.from(e,z.Internal)}}}}function go(e){let t=uo(e.next,e.interceptors),[n,r,i]=vo(e);return t(Object.assign(Object.assign({},e.req),{message:co(e.req.method.input,e.req.message),signal:n})).then(e=>(i(),e),r)}function _o(e){let[t,n,r]=vo(e),i=!1,a=new Promise(e=>{t.aborted?e():t.addEventListener(`abort`,()=>e())});return a.then(()=>{var n,r;let a=e.req.message[Symbol.asyncIterator]();if(!i){let e=B.from(Ka(t),z.Canceled);(n=a.throw)==null||n.call(a,e).catch(()=>{})}(r=a.return)==null||r.call(a).catch(()=>{})}),uo(async r=>{let o=await e.next(r),s=o.message[Symbol.asyncIterator]();return a.then(()=>s.return?.call(s).catch(()=>{})),Object.assign(Object.assign({},o),{message:{[Symbol.asyncIterator]:()=>({next:async()=>{let e=t.aborted?void 0:await Promise.race([s.next(),a]);return e===void 0?i?{done:!0,value:void 0}:n(Ka(t)):e}})}})},e.interceptors)(Object.assign(Object.assign({},e.req),{message:lo(e.req.method.input,e.req.message),signal:t})).then(e=>{let o=e.message[Symbol.asyncIterator](),s=a.then(async()=>{try{for(;(await o.next()).done!==!0;);}catch{}});return Object.assign(Object.assign({},e),{message:{[Symbol.asyncIterator]:()=>({async next(){if(t.aborted)return await s,i?{done:!0,value:void 0}:n(Ka(t));try{let e=await o.next();return e.done===!0&&(i=!0,r()),e}catch(e){return n(e)}},async return(e){return t.aborted||(i=!0,r()),await s,{done:!0,value:e}},async throw(e){if(i)throw B.from(e);try{return await n(e)}finally{await s}}})}})},n)}function vo(e){let{signal:t,cleanup:n}=Ga(e.timeoutMs),r=Wa(e.signal,t);return[r.signal,function(e){let t=r.signal.aborted?B.from(Ka(r.signal),z.Canceled):B.from(e);return r.abort(t),n(),Promise.reject(t)},function(){n(),r.abort()}]}var yo=Sr(`ChRuYWFkZi92MS9uYWFkZi5wcm90bxIIbmFhZGYudjEikgMKDEZyYW1lUmVxdWVzdBIOCgZjYW1lcmEYASABKAkSDQoFd2lkdGgYAiABKA0SDgoGaGVpZ2h0GAMgASgNEgwKBG1vZGUYBCABKAkSEwoLbWluX3ZlcnNpb24YBSABKAQSCwoDcmF3GAYgASgIEhIKCnRpbWVvdXRfbXMYByABKA0SCwoDc3BwGAggASgNEg4KBmZyYW1lcxgJIAEoDRIMCgRzZWVkGAogASgNEhQKB2JvdW5jZXMYCyABKA1IAIgBARILCgNza3kYDCABKAkSCwoDc3VuGA0gASgJEhAKCGV4cG9zdXJlGA4gASgCEg4KBnN0cmVhbRgPIAEoCRIcCg9yb21hX2RpcmVjdGlvbnMYECABKA1IAYgBARIVCghhb19yYW5nZRgRIAEoAkgCiAEBEhwKD2lycmFkaWFuY2VfcmF5cxgSIAEoDUgDiAEBQgoKCF9ib3VuY2VzQhIKEF9yb21hX2RpcmVjdGlvbnNCCwoJX2FvX3JhbmdlQhIKEF9pcnJhZGlhbmNlX3JheXMiWQoKRnJhbWVSZXBseRIPCgd2ZXJzaW9uGAEgASgEEg0KBXdpZHRoGAIgASgNEg4KBmhlaWdodBgDIAEoDRINCgVpbWFnZRgEIAEoDBIMCgRub2RlGAUgASgJImQKC05vZGVNZXNzYWdlEiQKBWhlbGxvGAEgASgLMhMubmFhZGYudjEuTm9kZUhlbGxvSAASJwoGcmVzdWx0GAIgASgLMhUubmFhZGYudjEuRnJhbWVSZXN1bHRIAEIGCgRraW5kIlIKCU5vZGVIZWxsbxIPCgdhZGFwdGVyGAEgASgJEg0KBW1vZGVzGAIgAygJEhEKCW1heF93aWR0aBgDIAEoDRISCgptYXhfaGVpZ2h0GAQgASgNIj8KCEZyYW1lSm9iEgoKAmlkGAEgASgEEicKB3JlcXVlc3QYAiABKAsyFi5uYWFkZi52MS5GcmFtZVJlcXVlc3QiZwoLRnJhbWVSZXN1bHQSCgoCaWQYASABKAQSDwoHdmVyc2lvbhgCIAEoBBINCgV3aWR0aBgDIAEoDRIOCgZoZWlnaHQYBCABKA0SDQoFaW1hZ2UYBSABKAwSDQoFZXJyb3IYBiABKAkisQEKC0pvaW5SZXF1ZXN0EhgKEHByb3RvY29sX3ZlcnNpb24YASABKA0SJgoGY2FjaGVkGAIgAygLMhYubmFhZGYudjEuQ2FjaGVkQnVmZmVyEiUKBnJlc3VtZRgDIAEoCzIVLm5hYWRmLnYxLlJlc3VtZVBvaW50EicKCmRlbHRhX2Zvcm0YBCABKA4yEy5uYWFkZi52MS5EZWx0YUZvcm0SEAoIcHJlc2VuY2UYBSABKAgiLgoLUmVzdW1lUG9pbnQSDwoHdmVyc2lvbhgBIAEoBBIOCgZkaWdlc3QYAiABKAYiMwoMQ2FjaGVkQnVmZmVyEg4KBmJ1ZmZlchgBIAEoDRITCgtwYWdlX2hhc2hlcxgCIAMoBiKkAQoMV29ybGRNZXNzYWdlEiIKBmhlYWRlchgBIAEoCzIQLm5hYWRmLnYxLkhlYWRlckgAEh4KBHBhZ2UYAiABKAsyDi5uYWFkZi52MS5QYWdlSAASIAoFZGVsdGEYAyABKAsyDy5uYWFkZi52MS5EZWx0YUgAEiYKCHByZXNlbmNlGAQgASgLMhIubmFhZGYudjEuUHJlc2VuY2VIAEIGCgRraW5kInIKD1ByZXNlbmNlUmVxdWVzdBIPCgdzZXNzaW9uGAEgASgGEgwKBG5hbWUYAiABKAkSEAoIcG9zaXRpb24YAyADKAESDwoHZm9yd2FyZBgEIAMoARIPCgdwb2ludGVyGAUgAygDEgwKBHRvb2wYBiABKAkiDwoNUHJlc2VuY2VSZXBseSI0CghQcmVzZW5jZRIoCgdlbnRyaWVzGAEgAygLMhcubmFhZGYudjEuUHJlc2VuY2VFbnRyeSKOAQoNUHJlc2VuY2VFbnRyeRIMCgR1c2VyGAEgASgJEg8KB3Nlc3Npb24YAiABKAYSDAoEbmFtZRgDIAEoCRIQCghwb3NpdGlvbhgEIAMoARIPCgdmb3J3YXJkGAUgAygBEg8KB3BvaW50ZXIYBiADKAMSDAoEdG9vbBgHIAEoCRIOCgZhZ2VfbXMYCCABKA0i5gEKBkhlYWRlchIYChBwcm90b2NvbF92ZXJzaW9uGAEgASgNEgwKBHNpemUYAiADKA0SDwoHdmVyc2lvbhgDIAEoBBISCgpncm93dGhfc2VxGAQgASgNEhEKCXF1aWVzY2VudBgFIAEoCBIOCgZkaWdlc3QYBiABKAYSJwoHYnVmZmVycxgHIAMoCzIWLm5hYWRmLnYxLkJ1ZmZlckxlbmd0aBIUCgxlbnRpdHlfdGFibGUYCCABKAwSDQoFcGFnZXMYCSABKA0SDgoGcmVzeW5jGAogASgIEg4KBnJlc3VtZRgLIAEoCCItCgxCdWZmZXJMZW5ndGgSDgoGYnVmZmVyGAEgASgNEg0KBWJ5dGVzGAIgASgEIjUKBFBhZ2USDgoGYnVmZmVyGAEgASgNEg8KB2luZGljZXMYAiADKA0SDAoEenN0ZBgDIAEoDCJVCgVEZWx0YRIOCgZjaGFuZ2UYASABKAwSDgoGZGlnZXN0GAIgASgGEgwKBHVzZXIYAyABKAkSHgoFcGF0Y2gYBCABKAsyDy5uYWFkZi52MS5QYXRjaCKTAQoFUGF0Y2gSDwoHdmVyc2lvbhgBIAEoBBISCgpncm93dGhfc2VxGAIgASgNEhEKCXF1aWVzY2VudBgDIAEoCBInCgdsZW5ndGhzGAQgAygLMhYubmFhZGYudjEuQnVmZmVyTGVuZ3RoEhsKBHJ1bnMYBSADKAsyDS5uYWFkZi52MS5SdW4SDAoEenN0ZBgGIAEoDCI0CgNSdW4SDgoGYnVmZmVyGAEgASgNEg4KBm9mZnNldBgCIAEoBBINCgVieXRlcxgDIAEoDCIjCgRSdW5zEhsKBHJ1bnMYASADKAsyDS5uYWFkZi52MS5SdW4iLgoLRWRpdFJlcXVlc3QSCwoDb3BzGAEgASgJEhIKCmNsaWVudF9zZXEYAiABKAQiLwoJRWRpdFJlcGx5Eg8KB3ZlcnNpb24YASABKAQSEQoJZHVwbGljYXRlGAIgASgIIjIKCkVudGl0eVBvc2USCgoCaWQYASABKA0SCwoDcG9zGAIgAygBEgsKA3JvdBgDIAMoASJTChRTcGF3bkVudGl0aWVzUmVxdWVzdBInCghlbnRpdGllcxgBIAMoCzIVLm5hYWRmLnYxLkVudGl0eVNwYXduEhIKCmNsaWVudF9zZXEYAiABKAQiQAoLRW50aXR5U3Bhd24SDQoFbW9kZWwYASABKAkSIgoEcG9zZRgCIAEoCzIULm5hYWRmLnYxLkVudGl0eVBvc2UiTgoTTW92ZUVudGl0aWVzUmVxdWVzdBIjCgVtb3ZlcxgBIAMoCzIULm5hYWRmLnYxLkVudGl0eVBvc2USEgoKY2xpZW50X3NlcRgCIAEoBCI5ChZEZXNwYXduRW50aXRpZXNSZXF1ZXN0EgsKA2lkcxgBIAMoDRISCgpjbGllbnRfc2VxGAIgASgEIiQKDkhpc3RvcnlSZXF1ZXN0EhIKCmNsaWVudF9zZXEYASABKAQiDwoNU3RhdHVzUmVxdWVzdCKqAQoLU3RhdHVzUmVwbHkSGAoQcHJvdG9jb2xfdmVyc2lvbhgBIAEoDRIMCgRzaXplGAIgAygNEg8KB3ZlcnNpb24YAyABKAQSEgoKZ3Jvd3RoX3NlcRgEIAEoDRIRCglxdWllc2NlbnQYBSABKAgSDgoGZGlnZXN0GAYgASgJEg8KB2NsaWVudHMYByABKA0SDAoEdXNlchgIIAEoCRIMCgRyb2xlGAkgASgJKjgKCURlbHRhRm9ybRIVChFERUxUQV9GT1JNX1JFQ09SRBAAEhQKEERFTFRBX0ZPUk1fUEFUQ0gQATKyBQoMV29ybGRTZXJ2aWNlEjcKBEpvaW4SFS5uYWFkZi52MS5Kb2luUmVxdWVzdBoWLm5hYWRmLnYxLldvcmxkTWVzc2FnZTABEjIKBEVkaXQSFS5uYWFkZi52MS5FZGl0UmVxdWVzdBoTLm5hYWRmLnYxLkVkaXRSZXBseRJECg1TcGF3bkVudGl0aWVzEh4ubmFhZGYudjEuU3Bhd25FbnRpdGllc1JlcXVlc3QaEy5uYWFkZi52MS5FZGl0UmVwbHkSQgoMTW92ZUVudGl0aWVzEh0ubmFhZGYudjEuTW92ZUVudGl0aWVzUmVxdWVzdBoTLm5hYWRmLnYxLkVkaXRSZXBseRJICg9EZXNwYXduRW50aXRpZXMSIC5uYWFkZi52MS5EZXNwYXduRW50aXRpZXNSZXF1ZXN0GhMubmFhZGYudjEuRWRpdFJlcGx5EjUKBFVuZG8SGC5uYWFkZi52MS5IaXN0b3J5UmVxdWVzdBoTLm5hYWRmLnYxLkVkaXRSZXBseRI1CgRSZWRvEhgubmFhZGYudjEuSGlzdG9yeVJlcXVlc3QaEy5uYWFkZi52MS5FZGl0UmVwbHkSOAoGU3RhdHVzEhcubmFhZGYudjEuU3RhdHVzUmVxdWVzdBoVLm5hYWRmLnYxLlN0YXR1c1JlcGx5Ej0KDFJlZ2lzdGVyTm9kZRIVLm5hYWRmLnYxLk5vZGVNZXNzYWdlGhIubmFhZGYudjEuRnJhbWVKb2IoATABEjsKC1JlbmRlckZyYW1lEhYubmFhZGYudjEuRnJhbWVSZXF1ZXN0GhQubmFhZGYudjEuRnJhbWVSZXBseRI9CgdQdWJsaXNoEhkubmFhZGYudjEuUHJlc2VuY2VSZXF1ZXN0GhcubmFhZGYudjEuUHJlc2VuY2VSZXBseWIGcHJvdG8z`),bo=R(yo,6),xo=R(yo,9),So=R(yo,10),Co=R(yo,20),wo=R(yo,21),To=R(yo,28),Eo=function(e){return e[e.RECORD=0]=`RECORD`,e[e.PATCH=1]=`PATCH`,e}({}),Do=io(yo,0),Oo=2**30,ko=Math.fround(.99999994);function Ao(e){let t;try{t=JSON.parse(e)}catch(e){throw Error(`camera JSON: ${e.message}`)}if(typeof t!=`object`||!t)throw Error(`camera JSON: not an object`);let n=t,r=n.pos;if(!Array.isArray(r)||r.length!==3||r.some(e=>typeof e!=`number`))throw Error(`camera JSON: pos must be three numbers`);for(let e of[`yaw`,`pitch`])if(typeof n[e]!=`number`)throw Error(`camera JSON: missing number ${e}`);if(n.fov_y!==void 0&&typeof n.fov_y!=`number`)throw Error(`camera JSON: fov_y must be a number`);let i={pos:[r[0],r[1],r[2]],yaw:n.yaw,pitch:n.pitch,fov_y:n.fov_y??90};if(![...i.pos,i.yaw,i.pitch,i.fov_y].every(Number.isFinite)||!(i.fov_y>0&&i.fov_y<180))throw Error(`camera values must be finite and 0 < fov_y < 180`);return i}function jo(e){return JSON.stringify({pos:e.pos,yaw:e.yaw,pitch:e.pitch,fov_y:e.fov_y})}var Mo=e=>Math.PI/180*e,No=(e,t)=>[e[1]*t[2]-e[2]*t[1],e[2]*t[0]-e[0]*t[2],e[0]*t[1]-e[1]*t[0]],Po=e=>{let t=Math.sqrt(e[0]*e[0]+e[1]*e[1]+e[2]*e[2]);return[e[0]/t,e[1]/t,e[2]/t]};function Fo(e){let t=Mo(e.yaw),n=Mo(Math.min(89.9,Math.max(-89.9,e.pitch))),r=[Math.sin(t)*Math.cos(n),Math.sin(n),Math.cos(t)*Math.cos(n)],i=Po(No([0,1,0],r));return{forward:r,right:i,up:No(r,i)}}function Io(e,t,n){if(e.pos.some(e=>Math.abs(e)>Oo))throw Error(`camera position is out of range (within ±2^30)`);let r=Fo(e),i=Math.tan(Mo(e.fov_y)/2),a=t/n,o=e.pos.map(Math.floor),s=e.pos.map((e,t)=>Math.min(Math.fround(e-o[t]),ko)),c=(e,t)=>e.map(e=>Math.fround(e*t));return{int:o,frac:s,forward:c(r.forward,1),right:c(r.right,i*a),up:c(r.up,i)}}function Lo(e){return{pos:[.5*e[0],.7*e[1],.05*e[2]],yaw:0,pitch:-15,fov_y:70}}function Ro(e,t,n,r){function i(e){return e instanceof n?e:new n(function(t){t(e)})}return new(n||=Promise)(function(n,a){function o(e){try{c(r.next(e))}catch(e){a(e)}}function s(e){try{c(r.throw(e))}catch(e){a(e)}}function c(e){e.done?n(e.value):i(e.value).then(o,s)}c((r=r.apply(e,t||[])).next())})}var V=class{constructor(){this.mutex=Promise.resolve()}lock(){let e=()=>{};return this.mutex=this.mutex.then(()=>new Promise(e)),new Promise(t=>{e=t})}dispatch(e){return Ro(this,void 0,void 0,function*(){let t=yield this.lock();try{return yield Promise.resolve(e())}finally{t()}})}};function zo(){return typeof globalThis<`u`?globalThis:typeof self<`u`?self:typeof window<`u`?window:global}var Bo=zo(),Vo=Bo.Buffer??null,Ho=Bo.TextEncoder?new Bo.TextEncoder:null;function Uo(e,t){return(e&15)+(e>>6|e>>3&8)<<4|(t&15)+(t>>6|t>>3&8)}function Wo(e,t){let n=t.length>>1;for(let r=0;r<n;r++){let n=r<<1;e[r]=Uo(t.charCodeAt(n),t.charCodeAt(n+1))}}function Go(e,t){if(e.length!==t.length*2)return!1;for(let n=0;n<t.length;n++){let r=n<<1;if(t[n]!==Uo(e.charCodeAt(r),e.charCodeAt(r+1)))return!1}return!0}var Ko=87,qo=48;function Jo(e,t,n){let r=0;for(let i=0;i<n;i++){let n=t[i]>>>4;e[r++]=n>9?n+Ko:n+qo,n=t[i]&15,e[r++]=n>9?n+Ko:n+qo}return String.fromCharCode.apply(null,e)}var Yo=Vo===null?e=>{if(typeof e==`string`)return Ho.encode(e);if(ArrayBuffer.isView(e))return new Uint8Array(e.buffer,e.byteOffset,e.byteLength);throw Error(`Invalid data type!`)}:e=>{if(typeof e==`string`){let t=Vo.from(e,`utf8`);return new Uint8Array(t.buffer,t.byteOffset,t.length)}if(Vo.isBuffer(e))return new Uint8Array(e.buffer,e.byteOffset,e.length);if(ArrayBuffer.isView(e))return new Uint8Array(e.buffer,e.byteOffset,e.byteLength);throw Error(`Invalid data type!`)},Xo=`ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/`,Zo=new Uint8Array(256);for(let e=0;e<64;e++)Zo[Xo.charCodeAt(e)]=e;function Qo(e){let t=Math.floor(e.length*.75),n=e.length;return e[n-1]===`=`&&(--t,e[n-2]===`=`&&--t),t}function $o(e){let t=Qo(e),n=e.length,r=new Uint8Array(t),i=0;for(let t=0;t<n;t+=4){let n=Zo[e.charCodeAt(t)],a=Zo[e.charCodeAt(t+1)],o=Zo[e.charCodeAt(t+2)],s=Zo[e.charCodeAt(t+3)];r[i]=n<<2|a>>4,i+=1,r[i]=(a&15)<<4|o>>2,i+=1,r[i]=(o&3)<<6|s&63,i+=1}return r}var es=16384,ts=4,ns=new V,rs=new Map;function is(e,t){return Ro(this,void 0,void 0,function*(){let n=null,r=null,i=!1;if(typeof WebAssembly>`u`)throw Error(`WebAssembly is not supported in this environment!`);let a=(e,t=0)=>{r.set(e,t)},o=()=>r,s=()=>n.exports,c=e=>{n.exports.Hash_SetMemorySize(e);let t=n.exports.Hash_GetBuffer(),i=n.exports.memory.buffer;r=new Uint8Array(i,t,e)},l=()=>new DataView(n.exports.memory.buffer).getUint32(n.exports.STATE_SIZE,!0),u=ns.dispatch(()=>Ro(this,void 0,void 0,function*(){if(!rs.has(e.name)){let t=$o(e.data),n=WebAssembly.compile(t.buffer);rs.set(e.name,n)}let t=yield rs.get(e.name);n=yield WebAssembly.instantiate(t,{})})),d=()=>Ro(this,void 0,void 0,function*(){n||(yield u);let e=n.exports.Hash_GetBuffer(),t=n.exports.memory.buffer;r=new Uint8Array(t,e,es)}),f=(e=null)=>{i=!0,n.exports.Hash_Init(e)},p=e=>{let t=0;for(;t<e.length;){let i=e.subarray(t,t+es);t+=i.length,r.set(i),n.exports.Hash_Update(i.length)}},m=e=>{if(!i)throw Error(`update() called before init()`);let t=Yo(e);p(t)},h=new Uint8Array(t*2),g=(e,a=null)=>{if(!i)throw Error(`digest() called before init()`);return i=!1,n.exports.Hash_Final(a),e===`binary`?r.slice(0,t):Jo(h,r,t)},_=()=>{if(!i)throw Error(`save() can only be called after init() and before digest()`);let t=n.exports.Hash_GetState(),r=l(),a=n.exports.memory.buffer,o=new Uint8Array(a,t,r),s=new Uint8Array(ts+r);return Wo(s,e.hash),s.set(o,ts),s},v=t=>{if(!(t instanceof Uint8Array))throw Error(`load() expects an Uint8Array generated by save()`);let r=n.exports.Hash_GetState(),a=l(),o=ts+a,s=n.exports.memory.buffer;if(t.length!==o)throw Error(`Bad state length (expected ${o} bytes, got ${t.length})`);if(!Go(e.hash,t.subarray(0,ts)))throw Error(`This state was written by an incompatible hash implementation`);let c=t.subarray(ts);new Uint8Array(s,r,a).set(c),i=!0},y=e=>typeof e==`string`?e.length<es/4:e.byteLength<es,b=y;switch(e.name){case`argon2`:case`scrypt`:b=()=>!0;break;case`blake2b`:case`blake2s`:b=(e,t)=>t<=512&&y(e);break;case`blake3`:b=(e,t)=>t===0&&y(e);break;case`xxhash64`:case`xxhash3`:case`xxhash128`:case`crc64`:b=()=>!1}return yield d(),{getMemory:o,writeMemory:a,getExports:s,setMemorySize:c,init:f,update:m,digest:g,save:_,load:v,calculate:(e,i=null,a=null)=>{if(!b(e,i))return f(i),m(e),g(`hex`,a);let o=Yo(e);return r.set(o),n.exports.Hash_Calculate(o.length,i,a),Jo(h,r,t)},hashLength:t}})}new V,new V,new V,new V,new V,new V,new V,new V,new V,new V,new V,new V,new V,new V,new V,new V,new V;var as={name:`xxhash3`,data:`AGFzbQEAAAABNAhgAAF/YAR/f39/AGAHf39/f39/fwBgBH9+fn4BfmAEf39/fgF+YAN/f34BfmAAAGABfwADDg0AAQIDBAUFBQYHBgAGBQQBAQICBg8CfwFBgIAEC38AQcCBBAsHggEJBm1lbW9yeQIAD19fc3RhY2tfcG9pbnRlcgMADkhhc2hfR2V0QnVmZmVyAAAJSGFzaF9Jbml0AAgLSGFzaF9VcGRhdGUACQpIYXNoX0ZpbmFsAAoNSGFzaF9HZXRTdGF0ZQALDkhhc2hfQ2FsY3VsYXRlAAwKU1RBVEVfU0laRQMBCo9CDQYAQYCCBAvzAwQBfwh+AX8IfgJAIANFDQAgA0EDdCEEIAApAzAhBSAAKQM4IQYgACkDICEHIAApAyghCCAAKQMQIQkgACkDGCEKIAApAwAhCyAAKQMIIQxBACENA0AgBiABQTBqKQMAIg58IAIgDWoiA0E4aikDACABQThqKQMAIg+FIgZCIIggBkL/////D4N+fCEGIAggAUEgaikDACIQfCADQShqKQMAIAFBKGopAwAiEYUiCEIgiCAIQv////8Pg358IQggCiABQRBqKQMAIhJ8IANBGGopAwAgAUEYaikDACIThSIKQiCIIApC/////w+DfnwhCiAMIAEpAwAiFHwgA0EIaikDACABQQhqKQMAIhWFIgxCIIggDEL/////D4N+fCEMIANBMGopAwAgDoUiDkIgiCAOQv////8Pg34gBXwgD3whBSADQSBqKQMAIBCFIg5CIIggDkL/////D4N+IAd8IBF8IQcgA0EQaikDACAShSIOQiCIIA5C/////w+DfiAJfCATfCEJIAMpAwAgFIUiDkIgiCAOQv////8Pg34gC3wgFXwhCyABQcAAaiEBIAQgDUEIaiINRw0ACyAAIAo3AxggACALNwMAIAAgDDcDCCAAIAg3AyggACAJNwMQIAAgBjcDOCAAIAc3AyAgACAFNwMwCwveAgIBfwF+AkAgBCACIAEoAgAiB2siAkkNACAAIAMgBSAHQQN0aiACEAEgACAFIAZqIgcpAwAgACkDACIIQi+IhSAIhUKx893xCX43AwAgACAHKQMIIAApAwgiCEIviIUgCIVCsfPd8Ql+NwMIIAAgBykDECAAKQMQIghCL4iFIAiFQrHz3fEJfjcDECAAIAcpAxggACkDGCIIQi+IhSAIhUKx893xCX43AxggACAHKQMgIAApAyAiCEIviIUgCIVCsfPd8Ql+NwMgIAAgBykDKCAAKQMoIghCL4iFIAiFQrHz3fEJfjcDKCAAIAcpAzAgACkDMCIIQi+IhSAIhUKx893xCX43AzAgACAHKQM4IAApAzgiCEIviIUgCIVCsfPd8Ql+NwM4IAAgAyACQQZ0aiAFIAQgAmsiBxABIAEgBzYCAA8LIAAgAyAFIAdBA3RqIAQQASABIAcgBGo2AgALewEBfyACIAGFIAOnIgRB/4H8B3FBCHggBEEYeEH/gfwHcXKtQiCGIAOFfUEANQKAhAVCIIYgAEH8gwVqNQIAhIUiA0IxiSADQhiJhSADhUKlvuP00YyH2Z9/fiIDQiOIIACtfCADhUKlvuP00YyH2Z9/fiIDQhyIIAOFC2QAIAMgAiABc618IgNCIYhBAC0AgIQFQRB0IABBCHRyIABBAXYtAICEBUEYdHIgAEH/gwVqLQAAcq2FIAOFQs/W077Sx6vZQn4iA0IdiCADhUL5893xmfaZqxZ+IgNCIIggA4ULhwMBBX4CQCAAQQlJDQBBACkDgIQFIAEpAyAgASkDGIUgAnyFIgNCOIYgA0KA/gODQiiGhCADQoCA/AeDQhiGIANCgICA+A+DQgiGhIQgA0IIiEKAgID4D4MgA0IYiEKAgPwHg4QgA0IoiEKA/gODIANCOIiEhIQgAK18IABB+IMFaikDACABKQMwIAEpAyiFIAJ9hSICfCACQv////8PgyIEIANCIIgiBX4iBiACQiCIIgIgA0L/////D4MiB358IgNCIIggAiAFfnxCgICAgBBCACADIAZUG3wgA0IghiIDIAQgB358IgIgA1StfCAChXwiA0IliCADhUL5893xmfKZqxZ+IgNCIIggA4UPCwJAIABBBEkNACAAIAFBCGopAwAgAUEQaikDACACEAMPCwJAIABFDQAgACABKAIAIAFBBGooAgAgAhAEDwsgASkDOCABKQNAhSAChSIDQiGIIAOFQs/W077Sx6vZQn4iA0IdiCADhUL5893xmfaZqxZ+IgNCIIggA4ULzggBB34gAK1Ch5Wvr5i23puef34hAwJAIABBIUkNAAJAIABBwQBJDQACQCAAQeEASQ0AIAEpA2ggAn1BACkDuIQFhSIEQv////8PgyIFIAEpA2AgAnxBACkDsIQFhSIGQiCIIgd+IgggBEIgiCIJIAZC/////w+DIgZ+fCIEQiCIIAkgB358QoCAgIAQQgAgBCAIVBt8IARCIIYiBCAFIAZ+fCIFIARUrXwgBYUgA3wgASkDeCACfSAAQciDBWopAwCFIgNC/////w+DIgQgASkDcCACfCAAQcCDBWopAwCFIgVCIIgiBn4iByADQiCIIgggBUL/////D4MiBX58IgNCIIggCCAGfnxCgICAgBBCACADIAdUG3wgA0IghiIDIAQgBX58IgQgA1StfCAEhXwhAwsgASkDSCACfUEAKQOohAWFIgRC/////w+DIgUgASkDQCACfEEAKQOghAWFIgZCIIgiB34iCCAEQiCIIgkgBkL/////D4MiBn58IgRCIIggCSAHfnxCgICAgBBCACAEIAhUG3wgBEIghiIEIAUgBn58IgUgBFStfCAFhSADfCABKQNYIAJ9IABB2IMFaikDAIUiA0L/////D4MiBCABKQNQIAJ8IABB0IMFaikDAIUiBUIgiCIGfiIHIANCIIgiCCAFQv////8PgyIFfnwiA0IgiCAIIAZ+fEKAgICAEEIAIAMgB1QbfCADQiCGIgMgBCAFfnwiBCADVK18IASFfCEDCyABKQMoIAJ9QQApA5iEBYUiBEL/////D4MiBSABKQMgIAJ8QQApA5CEBYUiBkIgiCIHfiIIIARCIIgiCSAGQv////8PgyIGfnwiBEIgiCAJIAd+fEKAgICAEEIAIAQgCFQbfCAEQiCGIgQgBSAGfnwiBSAEVK18IAWFIAN8IAEpAzggAn0gAEHogwVqKQMAhSIDQv////8PgyIEIAEpAzAgAnwgAEHggwVqKQMAhSIFQiCIIgZ+IgcgA0IgiCIIIAVC/////w+DIgV+fCIDQiCIIAggBn58QoCAgIAQQgAgAyAHVBt8IANCIIYiAyAEIAV+fCIEIANUrXwgBIV8IQMLIAEpAwggAn1BACkDiIQFhSIEQv////8PgyIFIAEpAwAgAnxBACkDgIQFhSIGQiCIIgd+IgggBEIgiCIJIAZC/////w+DIgZ+fCIEQiCIIAkgB358QoCAgIAQQgAgBCAIVBt8IARCIIYiBCAFIAZ+fCIFIARUrXwgBYUgA3wgASkDGCACfSAAQfiDBWopAwCFIgNC/////w+DIgQgASkDECACfCAAQfCDBWopAwCFIgJCIIgiBX4iBiADQiCIIgMgAkL/////D4MiB358IgJCIIggAyAFfnxCgICAgBBCACACIAZUG3wgAkIghiICIAQgB358IgMgAlStfCADhXwiAkIliCAChUL5893xmfKZqxZ+IgJCIIggAoUL5QoEAX8GfgJ/AX5BACEDIAEpA3ggAn1BACkD+IQFhSIEQv////8PgyIFIAEpA3AgAnxBACkD8IQFhSIGQiCIIgd+IgggBEIgiCIJIAZC/////w+DIgZ+fCIEQiCIIAkgB358QoCAgIAQQgAgBCAIVBt8IARCIIYiBCAFIAZ+fCIFIARUrXwgBYUgASkDaCACfUEAKQPohAWFIgRC/////w+DIgUgASkDYCACfEEAKQPghAWFIgZCIIgiB34iCCAEQiCIIgkgBkL/////D4MiBn58IgRCIIggCSAHfnxCgICAgBBCACAEIAhUG3wgBEIghiIEIAUgBn58IgUgBFStfCAFhSABKQNYIAJ9QQApA9iEBYUiBEL/////D4MiBSABKQNQIAJ8QQApA9CEBYUiBkIgiCIHfiIIIARCIIgiCSAGQv////8PgyIGfnwiBEIgiCAJIAd+fEKAgICAEEIAIAQgCFQbfCAEQiCGIgQgBSAGfnwiBSAEVK18IAWFIAEpA0ggAn1BACkDyIQFhSIEQv////8PgyIFIAEpA0AgAnxBACkDwIQFhSIGQiCIIgd+IgggBEIgiCIJIAZC/////w+DIgZ+fCIEQiCIIAkgB358QoCAgIAQQgAgBCAIVBt8IARCIIYiBCAFIAZ+fCIFIARUrXwgBYUgASkDOCACfUEAKQO4hAWFIgRC/////w+DIgUgASkDMCACfEEAKQOwhAWFIgZCIIgiB34iCCAEQiCIIgkgBkL/////D4MiBn58IgRCIIggCSAHfnxCgICAgBBCACAEIAhUG3wgBEIghiIEIAUgBn58IgUgBFStfCAFhSABKQMoIAJ9QQApA6iEBYUiBEL/////D4MiBSABKQMgIAJ8QQApA6CEBYUiBkIgiCIHfiIIIARCIIgiCSAGQv////8PgyIGfnwiBEIgiCAJIAd+fEKAgICAEEIAIAQgCFQbfCAEQiCGIgQgBSAGfnwiBSAEVK18IAWFIAEpAxggAn1BACkDmIQFhSIEQv////8PgyIFIAEpAxAgAnxBACkDkIQFhSIGQiCIIgd+IgggBEIgiCIJIAZC/////w+DIgZ+fCIEQiCIIAkgB358QoCAgIAQQgAgBCAIVBt8IARCIIYiBCAFIAZ+fCIFIARUrXwgBYUgASkDCCACfUEAKQOIhAWFIgRC/////w+DIgUgASkDACACfEEAKQOAhAWFIgZCIIgiB34iCCAEQiCIIgkgBkL/////D4MiBn58IgRCIIggCSAHfnxCgICAgBBCACAEIAhUG3wgBEIghiIEIAUgBn58IgUgBFStfCAFhSAArUKHla+vmLbem55/fnx8fHx8fHx8IgRCJYggBIVC+fPd8ZnymasWfiIEQiCIIASFIQUCQCAAQZABSQ0AIABBcHFBgH9qIQoDQCABIANqIgtBC2opAwAgAn0gA0GIhQVqKQMAhSIEQv////8PgyIGIAtBA2opAwAgAnwgA0GAhQVqKQMAhSIHQiCIIgh+IgkgBEIgiCIMIAdC/////w+DIgd+fCIEQiCIIAwgCH58QoCAgIAQQgAgBCAJVBt8IARCIIYiBCAGIAd+fCIGIARUrXwgBoUgBXwhBSAKIANBEGoiA0cNAAsLIAEpA38gAn0gAEH4gwVqKQMAhSIEQv////8PgyIGIAEpA3cgAnwgAEHwgwVqKQMAhSICQiCIIgd+IgggBEIgiCIEIAJC/////w+DIgl+fCICQiCIIAQgB358QoCAgIAQQgAgAiAIVBt8IAJCIIYiAiAGIAl+fCIEIAJUrXwgBIUgBXwiAkIliCAChUL5893xmfKZqxZ+IgJCIIggAoUL4QUCAX4BfwJAAkBBACkDgIIEIgBQRQ0AQYCABCEBQgAhAAwBCwJAIABBACkDoIYFUg0AQQAhAQwBC0EAIQFBAEKvr+/XvPeSoP4AIAB9NwP4gwVBACAAQsWW6/nY0oWCKHw3A/CDBUEAQo/x442tj/SYTiAAfTcD6IMFQQAgAEKrrPjF1e/R0Hx8NwPggwVBAELTrdSykoW1tJ5/IAB9NwPYgwVBACAAQpea9I71lrztyQB8NwPQgwVBAELFg4L9r//EsWsgAH03A8iDBUEAIABC6ouzncjm9PVDfDcDwIMFQQBCyL/6y5yb3rnkACAAfTcDuIMFQQAgAEKKo4Hf1JntrDF8NwOwgwVBAEL5ue+9/PjCpx0gAH03A6iDBUEAIABCqPXb+7Ocp5o/fDcDoIMFQQBCuLK8t5TVt9ZYIAB9NwOYgwVBACAAQvHIobqptMP8zgB8NwOQgwVBAEKIoZfbuOOUl6N/IAB9NwOIgwVBACAAQrzQyNqb8rCAS3w3A4CDBUEAQuDrwLSe0I6TzAAgAH03A/iCBUEAIABCuJGYovf+kJKOf3w3A/CCBUEAQoK1we7H+b+5ISAAfTcD6IIFQQAgAELL85n3xJnw8vgAfDcD4IIFQQBC8oCRpfr27LMfIAB9NwPYggVBACAAQt6pt8u+kOTLW3w3A9CCBUEAQvyChOTyvsjWHCAAfTcDyIIFQQAgAEK4/bPLs4Tppb5/fDcDwIIFC0EAQgA3A5CGBUEAQgA3A4iGBUEAQgA3A4CGBUEAQr3cypUMNwOAggVBAEKHla+vmLbem55/NwOIggVBAELP1tO+0ser2UI3A5CCBUEAQvnz3fGZ9pmrFjcDmIIFQQBC49zKlfzO8vWFfzcDoIIFQQBC95Svrwg3A6iCBUEAQsXP2bLx5brqJzcDsIIFQQBCsfPd8Qk3A7iCBUEAIAA3A6CGBUEAIAE2ArCGBUEAQpCAgICAEDcDmIYFC9YKAQh/QQBBACkDkIYFIACtfDcDkIYFAkACQAJAQQAoAoCGBSIBIABqIgJBgAJLDQAgAUGAhAVqIQNBgIIEIQQCQCAAQQhPDQAgACEFDAILQYCCBCEEAkACQCAAQXhqIgFBOHFBOEcNACAAIQUMAQtBgIIEIQQgAUEDdkEBakEHcSIGIQUDQCADIAQpAwA3AwAgA0EIaiEDIARBCGohBCAFQX9qIgUNAAsgACAGQQN0ayEFIAFBOEkNAgsDQCADIAQpAwA3AwAgA0EIaiAEQQhqKQMANwMAIANBEGogBEEQaikDADcDACADQRhqIARBGGopAwA3AwAgA0EgaiAEQSBqKQMANwMAIANBKGogBEEoaikDADcDACADQTBqIARBMGopAwA3AwAgA0E4aiAEQThqKQMANwMAIANBwABqIQMgBEHAAGohBCAFQUBqIgVBB0sNAAwCCwtBgIIEIQQgAEGAggRqIQZBACgCsIYFIgNBwIIFIAMbIQUCQCABRQ0AIAFBgIQFaiEDQYCCBCEEAkACQEGAAiABayIHQQhPDQAgByECDAELQYCCBCEEAkACQEH4ASABayIAQThxQThHDQAgByECDAELQQAgAEEDdkEBakEHcSIIayECQYCCBCEEA0AgAyAEKQMANwMAIANBCGohAyAEQQhqIQQgAkEBaiICDQALQYACIAEgCEEDdGprIQIgAEE4SQ0BCwNAIAMgBCkDADcDACADQQhqIARBCGopAwA3AwAgA0EQaiAEQRBqKQMANwMAIANBGGogBEEYaikDADcDACADQSBqIARBIGopAwA3AwAgA0EoaiAEQShqKQMANwMAIANBMGogBEEwaikDADcDACADQThqIARBOGopAwA3AwAgA0HAAGohAyAEQcAAaiEEIAJBQGoiAkEHSw0ACwsCQCACRQ0AAkACQCACQQdxIgANACACIQAMAQsDQCADIAQtAAA6AAAgA0EBaiEDIARBAWohBCAAQX9qIgANAAsgAkF4cSEACyACQQhJDQADQCADIAQpAAA3AAAgA0EIaiEDIARBCGohBCAAQXhqIgANAAsLQYCCBUGIhgVBACgCmIYFQYCEBUEEIAVBACgCnIYFEAJBAEEANgKAhgUgB0GAggRqIQQLAkAgBEGAAmogBk8NACAGQYB+aiECA0BBgIIFQYiGBUEAKAKYhgUgBCIDQQQgBUEAKAKchgUQAiADQYACaiIEIAJJDQALQQAgAykDwAE3A8CFBUEAIAMpA8gBNwPIhQVBACADKQPQATcD0IUFQQAgAykD2AE3A9iFBUEAIAMpA+ABNwPghQVBACADKQPoATcD6IUFQQAgAykD8AE3A/CFBUEAIAMpA/gBNwP4hQULQYCEBSEDAkACQCAGIARrIgJBCE8NACACIQUMAQtBgIQFIQMgAiEFA0AgAyAEKQMANwMAIANBCGohAyAEQQhqIQQgBUF4aiIFQQdLDQALCyAFRQ0BIAMgBC0AADoAACAFQQFGDQEgAyAELQABOgABIAVBAkYNASADIAQtAAI6AAIgBUEDRg0BIAMgBC0AAzoAAyAFQQRGDQEgAyAELQAEOgAEIAVBBUYNASADIAQtAAU6AAUgBUEGRg0BIAMgBC0ABjoABgwBCyAFRQ0AAkACQCAFQQdxIgINACAFIQIMAQsDQCADIAQtAAA6AAAgA0EBaiEDIARBAWohBCACQX9qIgINAAsgBUF4cSECCwJAIAVBCEkNAANAIAMgBCkAADcAACADQQhqIQMgBEEIaiEEIAJBeGoiAg0ACwtBACgCgIYFIABqIQILQQAgAjYCgIYFC8oSBQR/CH4BfxB+BX8jACIAIQEgAEGAAWtBQHEiAiQAQQAoArCGBSIAQcCCBSAAGyEDAkACQAJAAkACQAJAQQApA5CGBSIEQvEBVA0AIAJBACkDgIIFNwMAIAJBACkDiIIFIgU3AwggAkEAKQOQggUiBjcDECACQQApA5iCBSIHNwMYIAJBACkDoIIFIgg3AyAgAkEAKQOoggUiCTcDKCACQQApA7CCBSIKNwMwIAJBACkDuIIFIgs3AzgCQEEAKAKAhgUiDEHAAEkNACACQQAoAoiGBTYCQCACIAJBwABqQQAoApiGBUGAhAUgDEF/akEGdiADQQAoApyGBSIAEAIgAyAAaiIAQXlqKQMAIQ0gACkDCSEOIAApAxkhDyAAKQMpIQUgDEHAgwVqKQMAIQogACkDASELIAxByIMFaikDACEQIAxB0IMFaikDACEGIAApAxEhByAMQdiDBWopAwAhESAMQeCDBWopAwAhCCAAKQMhIQkgDEHogwVqKQMAIRIgAikDACETIAIpAxAhFCACKQMgIRUgAikDMCEWIAIpAwghFyACKQMYIRggAikDKCEZIAIgAikDOCAMQfCDBWopAwAiGnwgACkDMSAMQfiDBWopAwAiG4UiHEIgiCAcQv////8Pg358NwM4IBkgCHwgCSAShSIJQiCIIAlC/////w+DfnwhCSAYIAZ8IAcgEYUiB0IgiCAHQv////8Pg358IQcgFyAKfCALIBCFIgtCIIggC0L/////D4N+fCELIBsgFiAFIBqFIgVCIIggBUL/////D4N+fHwhBSASIBUgDyAIhSIIQiCIIAhC/////w+Dfnx8IQggESAUIA4gBoUiBkIgiCAGQv////8Pg358fCEGIBAgEyANIAqFIgpCIIggCkL/////D4N+fHwhCgwFCyAMQcCFBWohHUHAACAMayEeIAJBwABqIQACQCAMQThNDQAgHiEfDAMLAkBBOCAMa0EDdiIAQQdGDQBBACAAQQFqQQdxIiBrIR8gAkHAAGohAANAIAAgHSkDADcDACAAQQhqIQAgHUEIaiEdIB9BAWoiHw0AC0HAACAMICBBA3RqayEfDAILIAJBwABqIQAgHiEfA0AgACAdKQMANwMAIABBCGogHUEIaikDADcDACAAQRBqIB1BEGopAwA3AwAgAEEYaiAdQRhqKQMANwMAIABBIGogHUEgaikDADcDACAAQShqIB1BKGopAwA3AwAgAEEwaiAdQTBqKQMANwMAIABBOGogHUE4aikDADcDACAAQcAAaiEAIB1BwABqIR0gH0FAaiIfQQdLDQAMAgsLIASnIQACQEEAKQOghgUiBVANAAJAIARCEFYNACAAQYCABCAFEAUhBAwGCwJAIARCgAFWDQAgAEGAgAQgBRAGIQQMBgsgAEGAgAQgBRAHIQQMBQsCQCAEQhBWDQAgACADQgAQBSEEDAULAkAgBEKAAVYNACAAIANCABAGIQQMBQsgACADQgAQByEEDAQLIB9FDQELIB9Bf2ohIQJAIB9BB3EiIEUNAANAIAAgHS0AADoAACAAQQFqIQAgHUEBaiEdICBBf2oiIA0ACyAfQXhxIR8LICFBB0kNAANAIAAgHSkAADcAACAAQQhqIQAgHUEIaiEdIB9BeGoiHw0ACwsgAkHAAGogHmohHUGAhAUhAAJAIAxBCEkNACAMQXhqIiBBA3ZBAWohH0GAhAUhAANAIB0gACkDADcDACAdQQhqIR0gAEEIaiEAIB9Bf2oiHw0ACyAMICBBeHFrQXhqIQwLAkAgDEUNAAJAAkAgDEEHcSIfDQAgDCEfDAELA0AgHSAALQAAOgAAIB1BAWohHSAAQQFqIQAgH0F/aiIfDQALIAxBeHEhHwsgDEEISQ0AA0AgHSAAKQAANwAAIB1BCGohHSAAQQhqIQAgH0F4aiIfDQALCyADQQAoApyGBWoiAEF5aikDACETIAApAwkhFCAAKQMZIRUgACkDKSEWIAApAwEhFyAAKQMRIRggACkDISEZIAIpAwAhGiACKQNAIRAgAikDSCERIAIpA1AhEiACKQNYIQ0gAikDYCEOIAIpA2ghDyACIAsgAikDcCIbfCAAKQMxIAIpA3giHIUiC0IgiCALQv////8Pg358NwM4IAkgDnwgGSAPhSIJQiCIIAlC/////w+DfnwhCSAHIBJ8IBggDYUiB0IgiCAHQv////8Pg358IQcgBSAQfCAXIBGFIgVCIIggBUL/////D4N+fCELIBwgFiAbhSIFQiCIIAVC/////w+DfiAKfHwhBSAPIBUgDoUiCkIgiCAKQv////8Pg34gCHx8IQggDSAUIBKFIgpCIIggCkL/////D4N+IAZ8fCEGIBEgGiATIBCFIgpCIIggCkL/////D4N+fHwhCgsgAykDQyACKQM4hSIQQv////8PgyIRIAMpAzsgBYUiBUIgiCISfiINIBBCIIgiECAFQv////8PgyIOfnwiBUIgiCAQIBJ+fEKAgICAEEIAIAUgDVQbfCAFQiCGIgUgESAOfnwiECAFVK18IBCFIAMpAzMgCYUiBUL/////D4MiCSADKQMrIAiFIghCIIgiEH4iESAFQiCIIhIgCEL/////D4MiCH58IgVCIIggEiAQfnxCgICAgBBCACAFIBFUG3wgBUIghiIFIAkgCH58IgkgBVStfCAJhSADKQMjIAeFIgVC/////w+DIgkgAykDGyAGhSIHQiCIIgh+IgYgBUIgiCIQIAdC/////w+DIgd+fCIFQiCIIBAgCH58QoCAgIAQQgAgBSAGVBt8IAVCIIYiBSAJIAd+fCIJIAVUrXwgCYUgAykDEyALhSIFQv////8PgyIJIAMpAwsgCoUiB0IgiCILfiIIIAVCIIgiBiAHQv////8PgyIHfnwiBUIgiCAGIAt+fEKAgICAEEIAIAUgCFQbfCAFQiCGIgUgCSAHfnwiCSAFVK18IAmFIARCh5Wvr5i23puef358fHx8IgRCJYggBIVC+fPd8ZnymasWfiIEQiCIIASFIQQLQQAgBEI4hiAEQoD+A4NCKIaEIARCgID8B4NCGIYgBEKAgID4D4NCCIaEhCAEQgiIQoCAgPgPgyAEQhiIQoCA/AeDhCAEQiiIQoD+A4MgBEI4iISEhDcDgIIEIAEkAAsGAEGAggULAgALC80BAQBBgIAEC8QBuP5sOSOkS758AYEs9yGtHN7UbemDkJfbckCkpLezZx/LeeZOzMDleIJa0H3M/3IhuAhGdPdDJI7gNZDmgTomTDwoUruRwwDLiNBlixtTLqNxZEiXog35TjgZ70ap3qzYqPp2P+OcND/53LvHxwtPHYpR4EvNtFkxyJ9+ydl4c2TqxayDNNPrw8WBoP/6E2PrFw3dUbfw2knTFlUmKdRonisWvlh9R6H8j/i40XrQMc5FyzqPlRYEKK/X+8q7S0B+QAIAAA==`,hash:`8d0b08d4`};new V;function os(e){return!Number.isInteger(e)||e<0||e>0xffffffff?Error(`Seed must be given as two valid 32-bit long unsigned integers (lo + high).`):null}function ss(e,t,n){let r=new DataView(e);r.setUint32(0,t,!0),r.setUint32(4,n,!0)}function cs(e=0,t=0){return os(e)?Promise.reject(os(e)):os(t)?Promise.reject(os(t)):is(as,8).then(n=>{let r=new Uint8Array(8);ss(r.buffer,e,t),n.writeMemory(r),n.init();let i={init:()=>(n.writeMemory(r),n.init(),i),update:e=>(n.update(e),i),digest:e=>n.digest(e),save:()=>n.save(),load:e=>(n.load(e),i),blockSize:512,digestSize:8};return i})}new V,new V,new V,new V;var H=65536,ls;async function us(){ls??=await cs(0,0)}function ds(e,t,n){if(!ls)throw Error(`loadHasher() was not awaited`);let r=new Uint8Array(8),i=new DataView(r.buffer);return i.setUint32(0,e,!0),i.setUint32(4,t,!0),ls.init(),ls.update(r),ls.update(n),BigInt(`0x`+ls.digest(`hex`))}function fs(e){return e.toString(16).padStart(16,`0`)}var ps=ArrayBuffer,U=Uint8Array,ms=Uint16Array,hs=Int16Array,gs=Int32Array,_s=function(e,t,n){if(U.prototype.slice)return U.prototype.slice.call(e,t,n);(t==null||t<0)&&(t=0),(n==null||n>e.length)&&(n=e.length);var r=new U(n-t);return r.set(e.subarray(t,n)),r},vs=function(e,t,n,r){if(U.prototype.fill)return U.prototype.fill.call(e,t,n,r);for((n==null||n<0)&&(n=0),(r==null||r>e.length)&&(r=e.length);n<r;++n)e[n]=t;return e},ys=function(e,t,n,r){if(U.prototype.copyWithin)return U.prototype.copyWithin.call(e,t,n,r);for((n==null||n<0)&&(n=0),(r==null||r>e.length)&&(r=e.length);n<r;)e[t++]=e[n++]},bs=[`invalid zstd data`,`window size too large (>2046MB)`,`invalid block type`,`FSE accuracy too high`,`match distance too far back`,`unexpected EOF`],W=function(e,t,n){var r=Error(t||bs[e]);if(r.code=e,Error.captureStackTrace&&Error.captureStackTrace(r,W),!n)throw r;return r},xs=function(e,t,n){for(var r=0,i=0;r<n;++r)i|=e[t++]<<(r<<3);return i},Ss=function(e,t){return(e[t]|e[t+1]<<8|e[t+2]<<16|e[t+3]<<24)>>>0},Cs=function(e,t){var n=e[0]|e[1]<<8|e[2]<<16;if(n==3126568&&e[3]==253){var r=e[4],i=r>>5&1,a=r>>2&1,o=r&3,s=r>>6;r&8&&W(0);var c=6-i,l=o==3?4:o,u=xs(e,c,l);c+=l;var d=s?1<<s:i,f=xs(e,c,d)+(s==1&&256),p=f;if(!i){var m=1<<10+(e[5]>>3);p=m+(m>>3)*(e[5]&7)}p>0x7fe00000&&W(1);var h=new U((t==1?f||p:t?0:p)+12);return h[0]=1,h[4]=4,h[8]=8,{b:c+d,y:0,l:0,d:u,w:t&&t!=1?t:h.subarray(12),e:p,o:new gs(h.buffer,0,3),u:f,c:a,m:Math.min(131072,p)}}if((n>>4|e[3]<<20)==25481893)return Ss(e,4)+8;W(0)},ws=function(e){for(var t=0;1<<t<=e;++t);return t-1},Ts=function(e,t,n){var r=(t<<3)+4,i=(e[t]&15)+5;i>n&&W(3);for(var a=1<<i,o=a,s=-1,c=-1,l=-1,u=a,d=new ps(512+(a<<2)),f=new hs(d,0,256),p=new ms(d,0,256),m=new ms(d,512,a),h=512+(a<<1),g=new U(d,h,a),_=new U(d,h+a);s<255&&o>0;){var v=ws(o+1),y=r>>3,b=(1<<v+1)-1,x=(e[y]|e[y+1]<<8|e[y+2]<<16)>>(r&7)&b,S=(1<<v)-1,C=b-o-1,w=x&S;if(w<C?(r+=v,x=w):(r+=v+1,x>S&&(x-=C)),f[++s]=--x,x==-1?(o+=x,g[--u]=s):o-=x,!x)do{var T=r>>3;c=(e[T]|e[T+1]<<8)>>(r&7)&3,r+=2,s+=c}while(c==3)}(s>255||o)&&W(0);for(var E=0,ee=(a>>1)+(a>>3)+3,D=a-1,O=0;O<=s;++O){var k=f[O];if(k<1)p[O]=-k;else for(l=0;l<k;++l){g[E]=O;do E=E+ee&D;while(E>=u)}}for(E&&W(0),l=0;l<a;++l){var A=p[g[l]]++,j=_[l]=i-ws(A);m[l]=(A<<j)-a}return[r+7>>3,{b:i,s:g,n:_,t:m}]},Es=function(e,t){var n=0,r=-1,i=new U(292),a=e[t],o=i.subarray(0,256),s=i.subarray(256,268),c=new ms(i.buffer,268);if(a<128){var l=Ts(e,t+1,6),u=l[0],d=l[1];t+=a;var f=u<<3,p=e[t];p||W(0);for(var m=0,h=0,g=d.b,_=g,v=(++t<<3)-8+ws(p);v-=g,!(v<f);){var y=v>>3;if(m+=(e[y]|e[y+1]<<8)>>(v&7)&(1<<g)-1,o[++r]=d.s[m],v-=_,v<f)break;y=v>>3,h+=(e[y]|e[y+1]<<8)>>(v&7)&(1<<_)-1,o[++r]=d.s[h],g=d.n[m],m=d.t[m],_=d.n[h],h=d.t[h]}++r>255&&W(0)}else{for(r=a-127;n<r;n+=2){var b=e[++t];o[n]=b>>4,o[n+1]=b&15}++t}var x=0;for(n=0;n<r;++n){var S=o[n];S>11&&W(0),x+=S&&1<<S-1}var C=ws(x)+1,w=1<<C,T=w-x;for(T&T-1&&W(0),o[r++]=ws(T)+1,n=0;n<r;++n){var S=o[n];++s[o[n]=S&&C+1-S]}var E=new U(w<<1),ee=E.subarray(0,w),D=E.subarray(w);for(c[C]=0,n=C;n>0;--n){var O=c[n];vs(D,n,O,c[n-1]=O+s[n]*(1<<C-n))}for(c[0]!=w&&W(0),n=0;n<r;++n){var k=o[n];if(k){var A=c[k];vs(ee,n,A,c[k]=A+(1<<C-k))}}return[t,{n:D,b:C,s:ee}]},Ds=Ts(new U([81,16,99,140,49,198,24,99,12,33,196,24,99,102,102,134,70,146,4]),0,6)[1],Os=Ts(new U([33,20,196,24,99,140,33,132,16,66,8,33,132,16,66,8,33,68,68,68,68,68,68,68,68,36,9]),0,6)[1],ks=Ts(new U([32,132,16,66,102,70,68,68,68,68,36,73,2]),0,5)[1],As=function(e,t){for(var n=e.length,r=new gs(n),i=0;i<n;++i)r[i]=t,t+=1<<e[i];return r},js=new U(new gs([0,0,0,0,16843009,50528770,0x8070604,0xc0b0a09,269422093]).buffer,0,36),Ms=As(js,0),Ns=new U(new gs([0,0,0,0,0,0,0,0,16843009,50528770,0x7050404,0xb0a0908,0xf0e0d0c,16]).buffer,0,53),Ps=As(Ns,3),Fs=function(e,t,n){var r=e.length,i=t.length,a=e[r-1],o=(1<<n.b)-1,s=-n.b;a||W(0);for(var c=0,l=n.b,u=(r<<3)-8+ws(a)-l,d=-1;u>s&&d<i;){var f=u>>3,p=(e[f]|e[f+1]<<8|e[f+2]<<16)>>(u&7);c=(c<<l|p)&o,t[++d]=n.s[c],u-=l=n.n[c]}(u!=s||d+1!=i)&&W(0)},Is=function(e,t,n){var r=6,i=t.length+3>>2,a=i<<1,o=i+a;Fs(e.subarray(r,r+=e[0]|e[1]<<8),t.subarray(0,i),n),Fs(e.subarray(r,r+=e[2]|e[3]<<8),t.subarray(i,a),n),Fs(e.subarray(r,r+=e[4]|e[5]<<8),t.subarray(a,o),n),Fs(e.subarray(r),t.subarray(o),n)},Ls=function(e,t,n){var r,i=t.b,a=e[i],o=a>>1&3;t.l=a&1;var s=a>>3|e[i+1]<<5|e[i+2]<<13,c=(i+=3)+s;if(o==1)return i>=e.length?void 0:(t.b=i+1,n?(vs(n,e[i],t.y,t.y+=s),n):vs(new U(s),e[i]));if(!(c>e.length)){if(o==0)return t.b=c,n?(n.set(e.subarray(i,c),t.y),t.y+=s,n):_s(e,i,c);if(o==2){var l=e[i],u=l&3,d=l>>2&3,f=l>>4,p=0,m=0;u<2?d&1?f|=e[++i]<<4|(d&2&&e[++i]<<12):f=l>>3:(m=d,d<2?(f|=(e[++i]&63)<<4,p=e[i]>>6|e[++i]<<2):d==2?(f|=e[++i]<<4|(e[++i]&3)<<12,p=e[i]>>2|e[++i]<<6):(f|=e[++i]<<4|(e[++i]&63)<<12,p=e[i]>>6|e[++i]<<2|e[++i]<<10)),++i;var h=n?n.subarray(t.y,t.y+t.m):new U(t.m),g=h.length-f;if(u==0)h.set(e.subarray(i,i+=f),g);else if(u==1)vs(h,e[i++],g);else{var _=t.h;if(u==2){var v=Es(e,i);p+=i-(i=v[0]),t.h=_=v[1]}else _||W(0);(m?Is:Fs)(e.subarray(i,i+=p),h.subarray(g),_)}var y=e[i++];if(y){y==255?y=(e[i++]|e[i++]<<8)+32512:y>127&&(y=y-128<<8|e[i++]);var b=e[i++];b&3&&W(0);for(var x=[Os,ks,Ds],S=2;S>-1;--S){var C=b>>(S<<1)+2&3;if(C==1){var w=new U([0,0,e[i++]]);x[S]={s:w.subarray(2,3),n:w.subarray(0,1),t:new ms(w.buffer,0,1),b:0}}else C==2?(r=Ts(e,i,9-(S&1)),i=r[0],x[S]=r[1]):C==3&&(t.t||W(0),x[S]=t.t[S])}var T=t.t=x,E=T[0],ee=T[1],D=T[2],O=e[c-1];O||W(0);var k=(c<<3)-8+ws(O)-D.b,A=k>>3,j=0,te=(e[A]|e[A+1]<<8)>>(k&7)&(1<<D.b)-1;A=(k-=ee.b)>>3;var M=(e[A]|e[A+1]<<8)>>(k&7)&(1<<ee.b)-1;A=(k-=E.b)>>3;var ne=(e[A]|e[A+1]<<8)>>(k&7)&(1<<E.b)-1;for(++y;--y;){var re=D.s[te],ie=D.n[te],ae=E.s[ne],oe=E.n[ne],se=ee.s[M],N=ee.n[M];A=(k-=se)>>3;var ce=1<<se,P=ce+((e[A]|e[A+1]<<8|e[A+2]<<16|e[A+3]<<24)>>>(k&7)&ce-1);A=(k-=Ns[ae])>>3;var le=Ps[ae]+((e[A]|e[A+1]<<8|e[A+2]<<16)>>(k&7)&(1<<Ns[ae])-1);A=(k-=js[re])>>3;var ue=Ms[re]+((e[A]|e[A+1]<<8|e[A+2]<<16)>>(k&7)&(1<<js[re])-1);if(A=(k-=ie)>>3,te=D.t[te]+((e[A]|e[A+1]<<8)>>(k&7)&(1<<ie)-1),A=(k-=oe)>>3,ne=E.t[ne]+((e[A]|e[A+1]<<8)>>(k&7)&(1<<oe)-1),A=(k-=N)>>3,M=ee.t[M]+((e[A]|e[A+1]<<8)>>(k&7)&(1<<N)-1),P>3)t.o[2]=t.o[1],t.o[1]=t.o[0],t.o[0]=P-=3;else{var de=P-(ue!=0);de?(P=de==3?t.o[0]-1:t.o[de],de>1&&(t.o[2]=t.o[1]),t.o[1]=t.o[0],t.o[0]=P):P=t.o[0]}for(var S=0;S<ue;++S)h[j+S]=h[g+S];j+=ue,g+=ue;var fe=j-P;if(fe<0){var pe=-fe,me=t.e+fe;pe>le&&(pe=le);for(var S=0;S<pe;++S)h[j+S]=t.w[me+S];j+=pe,le-=pe,fe=0}for(var S=0;S<le;++S)h[j+S]=h[fe+S];j+=le}if(j!=g)for(;g<h.length;)h[j++]=h[g++];else j=h.length;n?t.y+=j:h=_s(h,0,j)}else if(n){if(t.y+=f,g)for(var S=0;S<f;++S)h[S]=h[g+S]}else g&&(h=_s(h,g));return t.b=c,h}W(2)}},Rs=function(e,t){if(e.length==1)return e[0];for(var n=new U(t),r=0,i=0;r<e.length;++r){var a=e[r];n.set(a,i),i+=a.length}return n};function zs(e,t){for(var n=[],r=+!t,i=0,a=0;e.length;){var o=Cs(e,r||t);if(typeof o==`object`){for(r?(t=null,o.w.length==o.u&&(n.push(t=o.w),a+=o.u)):(n.push(t),o.e=0);!o.l;){var s=Ls(e,o,t);s||W(5),t?o.e=o.y:(n.push(s),a+=s.length,ys(o.w,0,s.length),o.w.set(s,o.w.length-s.length))}i=o.b+o.c*4}else i=o;e=e.subarray(i)}return Rs(n,a)}var Bs=6,G=class extends Error{},Vs=class{id;bytes=new Uint8Array;len=0;hashes=[];stale=new Set;xor=0n;constructor(e){this.id=e}resize(e){if(e>this.bytes.length){let t=new Uint8Array(Math.max(e,Math.ceil(this.bytes.length*1.5)));t.set(this.bytes.subarray(0,this.len)),this.bytes=t}else e<this.len&&this.bytes.fill(0,e,this.len);let t=Math.ceil(e/H),n=this.hashes.length;this.len=e;for(let e=t;e<n;e++)this.xor^=this.hashes[e]??0n;this.hashes.length=t;for(let e of this.stale)e>=t&&this.stale.delete(e);for(let e=Math.max(0,Math.min(n,t)-1);e<t;e++)this.stale.add(e)}touch(e){this.stale.add(e)}settle(){for(let e of this.stale){let t=e*H,n=ds(this.id,e,this.bytes.subarray(t,Math.min(t+H,this.len)));this.xor^=(this.hashes[e]??0n)^n,this.hashes[e]=n}this.stale.clear()}digest(){return this.settle(),this.xor}},Hs=class{buffers=Array.from({length:8},(e,t)=>new Vs(t));size=[0,0,0];version=0n;growthSeq=0;quiescent=!1;digest=0n;holdsWorld=!1;expected;pagesLeft=0;cached(){return this.buffers.map(e=>(e.settle(),{buffer:e.id,pageHashes:[...e.hashes]}))}bytes(e){let t=this.buffers[e];return t.bytes.subarray(0,t.len)}words(e){let t=this.bytes(e);return new Uint32Array(t.buffer,t.byteOffset,t.length>>2)}restore(e,t){if(t.length!==8||e.lengths.length!==8)return!1;for(let n=0;n<8;n++){let r=this.buffers[n];r.resize(e.lengths[n]),t[n].forEach((e,t)=>{r.bytes.set(e.subarray(0,Math.max(0,Math.min(H,r.len-t*H))),t*H),r.touch(t)})}return this.size=e.size,this.version=e.version,this.growthSeq=e.growthSeq,this.quiescent=e.quiescent,this.digest=this.computeDigest(),this.holdsWorld=this.digest===e.digest,this.holdsWorld}header(e){if(e.resume){if(!this.holdsWorld||e.version!==this.version||e.digest!==this.digest)throw new G(`the server resumed a state this page does not hold`);return this.growthSeq=e.growthSeq,this.quiescent=e.quiescent,!1}if(e.size.length!==3)throw new G(`the header's world size is not three numbers`);this.holdsWorld=!1,this.size=[e.size[0],e.size[1],e.size[2]];for(let t of e.buffers)if(t.buffer>=8)throw new G(`the header names buffer ${t.buffer}`);for(let t=0;t<8;t++){let n=e.buffers.find(e=>e.buffer===t);if(!n&&t<Bs)throw new G(`the header lacks the length of buffer ${t}`);this.buffers[t].resize(n?Number(n.bytes):0)}return this.expected=e,this.pagesLeft=e.pages,this.pagesLeft===0&&this.finishSnapshot(),this.pagesLeft>0}page(e){if(!this.expected||this.pagesLeft===0)throw new G(`a page arrived outside a snapshot`);let t=this.buffers[e.buffer];if(!t)throw new G(`a page of buffer ${e.buffer}`);let n=zs(e.zstd),r=0;for(let i of e.indices){let a=i*H,o=Math.min(H,t.len-a);if(o<=0||r+o>n.length)throw new G(`page ${i} of buffer ${e.buffer} does not fit`);t.bytes.set(n.subarray(r,r+o),a),r+=o,t.touch(i)}return--this.pagesLeft,this.pagesLeft===0&&(this.finishSnapshot(),!0)}finishSnapshot(){let e=this.expected;if(this.version=e.version,this.growthSeq=e.growthSeq,this.quiescent=e.quiescent,this.digest=this.computeDigest(),this.expected=void 0,this.digest!==e.digest)throw new G(`the snapshot's pages do not give the header's digest`);this.holdsWorld=!0}delta(e){let t=e.patch;if(!this.holdsWorld)throw new G(`a delta arrived before a snapshot`);if(!t)throw new G(`a delta without a patch (the page joins in the patch form)`);for(let e of t.lengths){let t=this.buffers[e.buffer];if(!t)throw new G(`a patch resizes buffer ${e.buffer}`);t.resize(Number(e.bytes))}let n=t.zstd.length>0?sr(Co,zs(t.zstd)).runs:t.runs,r=[];for(let e of n){let t=this.buffers[e.buffer],n=Number(e.offset),i=n+e.bytes.length;if(!t||i>t.len)throw new G(`a run reaches past buffer ${e.buffer}`);t.bytes.set(e.bytes,n);for(let e=Math.floor(n/H);e*H<i;e++)t.touch(e);r.push({id:e.buffer,lo:n,hi:i})}if(this.version=t.version,this.growthSeq=t.growthSeq,this.quiescent=t.quiescent,this.digest=this.computeDigest(),this.digest!==e.digest)throw this.holdsWorld=!1,new G(`the page diverged from the server at version ${t.version}`);return{touched:r,resized:t.lengths.length>0}}computeDigest(){let e=0n;for(let t of this.buffers)e^=t.digest();return e}},Us=`naadf`,Ws=`pages`,Gs=`states`,Ks=(e,t)=>`${e}:${t.toString(16)}`;function qs(e){return new Promise((t,n)=>{e.onsuccess=()=>t(e.result),e.onerror=()=>n(e.error)})}function Js(e){return new Promise((t,n)=>{e.oncomplete=()=>t(),e.onerror=e.onabort=()=>n(e.error)})}var Ys=class e{db;constructor(e){this.db=e}static async open(){try{let t=indexedDB.open(Us,1);return t.onupgradeneeded=()=>{t.result.createObjectStore(Ws),t.result.createObjectStore(Gs)},new e(await qs(t))}catch{return}}async restore(e){let t=this.db.transaction([Ws,Gs],`readonly`),n=await qs(t.objectStore(Gs).get(location.origin));if(!n)return!1;let r=t.objectStore(Ws),i=n.hashes.map((e,t)=>Promise.all(e.map(e=>qs(r.get(Ks(t,e)))))),a=await Promise.all(i);return!a.some(e=>e.some(e=>!e))&&e.restore(n,a)}async save(e){if(!e.holdsWorld)return;let t=this.db.transaction([Ws,Gs],`readwrite`),n=t.objectStore(Ws),r=new Set((await qs(n.getAllKeys())).map(String)),i=new Set,a=[],o=[];for(let t=0;t<8;t++){let s=e.buffers[t];s.settle(),o.push(s.len),a.push([...s.hashes]),s.hashes.forEach((e,a)=>{let o=Ks(t,e);i.add(o),r.has(o)||n.put(s.bytes.slice(a*H,Math.min((a+1)*H,s.len)),o)})}for(let e of r)i.has(e)||n.delete(e);let s={size:e.size,version:e.version,growthSeq:e.growthSeq,quiescent:e.quiescent,digest:e.digest,lengths:o,hashes:a};t.objectStore(Gs).put(s,location.origin),await Js(t)}},Xs=`// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the
// Rust code, the world's storage bindings.
struct WorldInfo {
    // World size in voxels.
    size: vec3<u32>,
    // Slots of the instance buffer on the device, the world's and then the local
    // instances' (records of 5 words; 0: no instance to trace).
    instance_slots: u32,
    // World size in chunks.
    chunks: vec3<u32>,
    // Cells a ray may visit before it counts as a miss.
    max_steps: u32,
}
@group(0) @binding(0) var<uniform> world_info: WorldInfo;
struct FrameInfo {
    // Camera position, integer part (floor).
    cam_int: vec3<i32>,
    // Image width in pixels.
    width: u32,
    // Camera position, fractional part in [0, 1).
    cam_frac: vec3<f32>,
    // Image height in pixels.
    height: u32,
    // View direction.
    forward: vec3<f32>,
    // The run's seed.
    seed: u32,
    // Image right, scaled by a·W/H.
    right: vec3<f32>,
    // Number of the sample this dispatch adds.
    sample: u32,
    // Image up, scaled by a.
    up: vec3<f32>,
    // 1 when a temporal pass has a history to blend with (0 for the path tracer).
    history: u32,
}
struct LightInfo {
    // Uniform sky: its radiance. Physical sky: the irradiance of the sun lighting it.
    sky: vec3<f32>,
    // 1 for the physical sky.
    sky_physical: u32,
    // Unit vector toward the sun (the sun lighting the physical sky when it is off).
    sun_dir: vec3<f32>,
    // 1 when the sun shines (its disc and its samples).
    sun_on: u32,
    // The disc's radiance.
    sun_disc: f32,
    // The weight of one disc sample: radiance times solid angle.
    sun_weight: f32,
    // 1 − cos of the disc's angular radius.
    sun_omc: f32,
    // Scattered rays after the camera ray.
    bounces: u32,
}
struct GiInfo {
    // Frames rendered in this history before this one.
    frame: u32,
    // The long-term TAA slot this frame writes (\`frame % TAA_SLOTS\`).
    taa_slot: u32,
    // Earlier frames the TAA may read (at most \`TAA_SLOTS − 1\`).
    taa_valid: u32,
    // The first frame rendered after the newest change of the materials, or of more
    // chunks than are marked one by one (0: none): the near-change rule everywhere.
    edit_frame: u32,
    // The first frame rendered after the newest change of any chunk, entity moves
    // included (0: none): the still path keeps no sample from before it.
    change_frame: u32,
    // This frame's jitter in the pixel, x (a point of a 32-point (0, 5, 2)-net).
    jitter_x: f32,
    // This frame's jitter in the pixel, y.
    jitter_y: f32,
    // 8×8 regions across.
    regions_x: u32,
    // 8×8 regions down.
    regions_y: u32,
    // Samples the sample ring holds.
    ring_capacity: u32,
    // 1 when the bilateral denoiser runs.
    denoise: u32,
    // Where each pixel's own secondary sample starts in \`mem\` (tagged with the
    // frame that traced it).
    off_own: u32,
    // Where the atmosphere table starts in \`mem\` (vec4 words; the cameras start at 0).
    off_lut: u32,
    // Where the first-hit surfaces start in \`mem\`.
    off_gbuf: u32,
    // Where the first-hit materials start in \`mem\`.
    off_gmat: u32,
    // Where the first-hit light starts in \`mem\`.
    off_emitted: u32,
    // Where the TAA's per-pixel sums and ranges start in \`mem\`.
    off_taa_info: u32,
    // Where the incoming light starts in \`mem\`.
    off_illum: u32,
    // Where the denoiser's intermediate starts in \`mem\`.
    off_illum2: u32,
    // Where the results start in \`mem\`.
    off_result: u32,
    // Where the refined samples start in \`mem\`.
    off_refined: u32,
    // Where the regions' statistics start in \`mem\`.
    off_region_info: u32,
    // Where the sample ring starts in \`mem\`.
    off_ring: u32,
    // Where the queued pixels start in \`words\`.
    off_queue_list: u32,
}
const STATE_SHIFT: u32 = 30u;
const STATE_EMPTY: u32 = 0u;
const STATE_FULL: u32 = 1u;
const STATE_MIXED: u32 = 2u;
const PAYLOAD: u32 = 1073741823u;
const MAX_MATERIAL: u32 = 32767u;
const VOXEL_SOLID: u32 = 32768u;
const CHUNK_FIELD_BITS: u32 = 5u;
const CELL_FIELD_BITS: u32 = 2u;
const KIND_DIFFUSE: u32 = 0u;
const KIND_EMISSIVE: u32 = 1u;
const KIND_METAL: u32 = 2u;
const KIND_MIRROR: u32 = 3u;
const ENTITY_SOLID: u32 = 2147483648u;
const TYPE_ALIGN: u32 = 64u;
const RECORD_WORDS: u32 = 5u;
const NO_ENTITY: u32 = 16383u;
const NODE_WORDS: u32 = 28u;
const BVH_STACK: u32 = 64u;
const BVH_LEAF: u32 = 2147483648u;
const BVH_NONE: u32 = 4294967295u;
const BVH_FAR: f32 = 1e30f;
const SURFACE_OFFSET: f32 = 0.01f;
const MIN_ALPHA: f32 = 0.001f;
const PI: f32 = 3.1415927f;
const PLANET_RADIUS: f32 = 6360000.0f;
const ATMOSPHERE_HEIGHT: f32 = 60000.0f;
const EYE_HEIGHT: f32 = 100.0f;
const VIEW_STEPS: u32 = 24u;
const LIGHT_STEPS: u32 = 6u;
const RAYLEIGH: vec3<f32> = vec3<f32>(5.802e-6f, 1.3558e-5f, 3.31e-5f);
const RAYLEIGH_SCALE: f32 = 8000.0f;
const MIE_SCATTER: f32 = 3.996e-6f;
const MIE_EXTINCTION: f32 = 4.44e-6f;
const MIE_SCALE: f32 = 1200.0f;
const MIE_G: f32 = 0.8f;
const OZONE: vec3<f32> = vec3<f32>(6.5e-7f, 1.881e-6f, 8.5e-8f);
const OZONE_CENTRE: f32 = 25000.0f;
const OZONE_HALF_WIDTH: f32 = 15000.0f;
// The first word of each buffer in \`world\`.
struct WorldOffsets {
    chunks: u32,
    blocks: u32,
    voxels: u32,
    materials: u32,
    entity_types: u32,
    entity_instances: u32,
    entity_hierarchy: u32,
    structure: u32,
}
@group(0) @binding(1) var<uniform> world_offsets: WorldOffsets;
@group(0) @binding(2) var<storage, read> world: array<u32>;
fn chunk_word(i: u32) -> u32 { return world[world_offsets.chunks + i]; }
fn block_word(i: u32) -> u32 { return world[world_offsets.blocks + i]; }
fn voxel_word(i: u32) -> u32 { return world[world_offsets.voxels + i]; }
fn material_word(i: u32) -> u32 { return world[world_offsets.materials + i]; }
fn entity_type_word(i: u32) -> u32 { return world[world_offsets.entity_types + i]; }
fn instance_word(i: u32) -> u32 { return world[world_offsets.entity_instances + i]; }
fn hierarchy_word(i: u32) -> u32 { return world[world_offsets.entity_hierarchy + i]; }
fn structure_word(i: u32) -> u32 { return world[world_offsets.structure + i]; }

// The world buffers (docs/FORMAT.md §5) and how to read their cells.
//
// Generated by naadf-client (client/src/gpu/shaders.rs) from the Rust definitions, in the
// prelude before this file:
// - the parameters \`world_info: WorldInfo\` (size in voxels and chunks, the instance
//   buffer's slots, the step budget);
// - the constants of the cell layout (STATE_*, PAYLOAD, MAX_MATERIAL, VOXEL_SOLID,
//   CHUNK_FIELD_BITS, CELL_FIELD_BITS), the material kinds (KIND_*), the entity layout
//   (ENTITY_SOLID, TYPE_ALIGN, RECORD_WORDS, NO_ENTITY), the instance hierarchy's (NODE_WORDS,
//   BVH_*) and the frame modes (MODE_*);
// - the storage bindings and the accessors \`chunk_word\`, \`block_word\`, \`voxel_word\`,
//   \`material_word\`, \`entity_type_word\`, \`instance_word\`, \`hierarchy_word\` (and
//   \`structure_word\` for the comparison traversals): a buffer larger than the adapter's
//   storage-binding limit is split across several bindings, and the accessor picks the
//   part.

// State of a chunk or block cell: STATE_EMPTY, STATE_FULL or (also for state 3)
// STATE_MIXED.
fn cell_state(c: u32) -> u32 {
    return min(c >> STATE_SHIFT, STATE_MIXED);
}

// Field \`dir\` (order −x, +x, −y, +y, −z, +z) of a packed AADF.
fn aadf_field(word: u32, dir: u32, bits: u32) -> u32 {
    return (word >> (bits * dir)) & ((1u << bits) - 1u);
}

// The index of chunk \`c\` in a world of \`chunks\` chunks (\`world_info.chunks\`). Loops read
// \`world_info\` once before they start and pass its fields: it is a storage buffer, and a
// storage read in every step is a bounds-checked load on lavapipe.
fn chunk_index(c: vec3<u32>, chunks: vec3<u32>) -> u32 {
    return c.x + chunks.x * (c.y + chunks.y * c.z);
}

fn index4(p: vec3<u32>) -> u32 {
    return p.x + 4u * p.y + 16u * p.z;
}

// Voxel \`i\` (0..64) of the voxel group starting at word \`ptr\`.
fn group_voxel(ptr: u32, i: u32) -> u32 {
    return (voxel_word(ptr + i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

// A material's entry (docs/FORMAT.md §5.4).
struct Material {
    kind: u32,
    albedo: vec3<f32>,
    emission: f32,
    roughness: f32,
}

fn material(id: u32) -> Material {
    let w0 = material_word(4u * id);
    let w1 = material_word(4u * id + 1u);
    let w2 = material_word(4u * id + 2u);
    let rg = unpack2x16float(w1);
    let be = unpack2x16float(w2);
    return Material(w0 & 3u, vec3<f32>(rg.x, rg.y, be.x), be.y, unpack2x16float(w0).y);
}

// Rays and the event model every traversal shares (world/src/traverse/ray.rs, in f32).
//
// A ray keeps its origin split into an integer part \`o_int\` and a fraction \`o_frac\` in [0, 1)
// (docs/NAADF.md §9), so precision does not depend on where in the world it starts.
// The direction \`d\` is kept exactly as given (not renormalised, which would move the line
// by an f32 rounding): times are in units of |d| and the ray's \`len\` converts them to
// distances. Every decision compares plane-crossing times from the one function \`t_at\`,
// so the traversal is a consistent walk of the event order "(t, axis), x before y before
// z at equal t"; it departs from the CPU's f64 order only where two crossings are within
// f32 rounding of each other.

// A cell bound beyond any world for unconstrained axes (the CPU walk uses 2^40, which no
// i32 holds).
const FAR_CELL: i32 = 1073741824;
const T_INF: f32 = 3.0e38;
const NO_AXIS: u32 = 3u;

struct Ray {
    o_int: vec3<i32>,
    o_frac: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    len: f32,
}

fn ray_new(o_int: vec3<i32>, o_frac: vec3<f32>, d: vec3<f32>) -> Ray {
    // The inverse of a zero component is never read: such axes never cross a plane.
    let safe = select(vec3<f32>(1.0), d, d != vec3<f32>(0.0));
    return Ray(o_int, o_frac, d, 1.0 / safe, length(d));
}

// A ray from an unsplit origin.
fn ray_from(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(o);
    return ray_new(vec3<i32>(fl), min(o - fl, vec3<f32>(0.99999994)), d);
}

// The ray's point at time \`t\`, relative to its integer origin.
fn ray_local(r: Ray, t: f32) -> vec3<f32> {
    return r.o_frac + r.d * t;
}

// A ray starting at \`p\` (relative to \`r\`'s integer origin) along \`d\`.
fn ray_at(r: Ray, p: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(p);
    return ray_new(r.o_int + vec3<i32>(fl), min(p - fl, vec3<f32>(0.99999994)), d);
}

// Time at which the ray crosses plane \`k\` of \`axis\`.
fn t_at(r: Ray, a: u32, k: i32) -> f32 {
    return (f32(k - r.o_int[a]) - r.o_frac[a]) * r.inv[a];
}

// Whether the crossing of plane \`k\` of axis \`b\` comes before the event \`(t, a)\`.
fn crossed(r: Ray, b: u32, k: i32, t: f32, a: u32) -> bool {
    let tb = t_at(r, b, k);
    return tb < t || (tb == t && b < a);
}

// The cell of axis \`b\` right after event \`(t, a)\`, known to lie in \`lo..=hi\`.
fn cell_after(r: Ray, b: u32, t: f32, a: u32, lo: i32, hi: i32) -> i32 {
    let d = r.d[b];
    if lo == hi || d == 0.0 {
        return lo;
    }
    let p = r.o_frac[b] + d * t;
    let fl = floor(p);
    var k = clamp(i32(fl) + r.o_int[b], lo, hi);
    let f = p - fl;
    // Far from a plane the floor is certain; near one, decide by crossing times.
    let tol = 4e-6 * (abs(d * t) + 1.0);
    if f > tol && f < 1.0 - tol {
        return k;
    }
    if d > 0.0 {
        while k < hi && crossed(r, b, k + 1, t, a) {
            k += 1;
        }
        while k > lo && !crossed(r, b, k, t, a) {
            k -= 1;
        }
    } else {
        while k > lo && crossed(r, b, k, t, a) {
            k -= 1;
        }
        while k < hi && !crossed(r, b, k + 1, t, a) {
            k += 1;
        }
    }
    return k;
}

// Where a ray begins inside the box [0, size): its first cell, the time it is entered and
// the axis whose plane it crossed (NO_AXIS when the origin is inside). \`ok\` is false when
// the ray misses the box.
struct Entry {
    cell: vec3<i32>,
    t: f32,
    axis: u32,
    ok: bool,
}

fn ray_entry(r: Ray, size: vec3<i32>) -> Entry {
    let start = r.o_int;
    var miss = Entry(vec3<i32>(0), 0.0, NO_AXIS, false);
    if all(start >= vec3<i32>(0)) && all(start < size) {
        return Entry(start, 0.0, NO_AXIS, true);
    }
    // The last slab-entry event, in (t, axis) order.
    var bt = 0.0;
    var ba = NO_AXIS;
    for (var a = 0u; a < 3u; a++) {
        var plane: i32;
        if start[a] < 0 {
            if r.d[a] <= 0.0 {
                return miss;
            }
            plane = 0;
        } else if start[a] >= size[a] {
            if r.d[a] >= 0.0 {
                return miss;
            }
            plane = size[a];
        } else {
            continue;
        }
        let t = t_at(r, a, plane);
        if ba == NO_AXIS || t >= bt {
            bt = t;
            ba = a;
        }
    }
    var cell = vec3<i32>(0);
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            cell[b] = select(size[b] - 1, 0, r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            cell[b] = cell_after(r, b, bt, ba, start[b], FAR_CELL);
        } else if r.d[b] < 0.0 {
            cell[b] = cell_after(r, b, bt, ba, -FAR_CELL, start[b]);
        } else {
            cell[b] = start[b];
        }
    }
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return miss;
    }
    return Entry(cell, bt, ba, true);
}

// When a ray inside the box [0, size] leaves it: the first crossing of a far plane it moves
// toward (world/src/traverse/ray.rs \`leave_time\`).
fn leave_time(r: Ray, size: vec3<i32>) -> f32 {
    var t = T_INF;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            t = min(t, t_at(r, a, select(0, size[a], r.d[a] > 0.0)));
        }
    }
    return t;
}

// Leaving the empty cuboid made of \`cell\` extended by \`skip\` cells toward the ray on each
// axis: the exit event and the cell entered by it.
struct Exit {
    t: f32,
    axis: u32,
    next: vec3<i32>,
}

fn ray_exit(r: Ray, cell: vec3<i32>, skip: vec3<i32>) -> Exit {
    var bound = vec3<i32>(0);
    var bt = T_INF;
    var ba = 0u;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] == 0.0 {
            continue;
        }
        bound[a] = select(cell[a] - skip[a], cell[a] + 1 + skip[a], r.d[a] > 0.0);
        let t = t_at(r, a, bound[a]);
        if t < bt {
            bt = t;
            ba = a;
        }
    }
    var next = cell;
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            next[b] = select(bound[b] - 1, bound[b], r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b], cell[b] + skip[b]);
        } else if r.d[b] < 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b] - skip[b], cell[b]);
        }
    }
    return Exit(bt, ba, next);
}

// Amanatides–Woo state in the same event order (ties step the lowest axis first).
struct Dda {
    cell: vec3<i32>,
    tmax: vec3<f32>,
    t: f32,
    axis: u32,
}

fn dda_start(r: Ray, e: Entry) -> Dda {
    var tmax = vec3<f32>(T_INF);
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            tmax[a] = t_at(r, a, select(e.cell[a], e.cell[a] + 1, r.d[a] > 0.0));
        }
    }
    return Dda(e.cell, tmax, e.t, e.axis);
}

fn dda_advance(r: Ray, s: ptr<function, Dda>) {
    var a = 0u;
    if (*s).tmax[1] < (*s).tmax[a] {
        a = 1u;
    }
    if (*s).tmax[2] < (*s).tmax[a] {
        a = 2u;
    }
    (*s).t = (*s).tmax[a];
    let c = (*s).cell[a] + select(-1, 1, r.d[a] > 0.0);
    (*s).cell[a] = c;
    (*s).axis = a;
    (*s).tmax[a] = t_at(r, a, select(c, c + 1, r.d[a] > 0.0));
}

// The first solid voxel along a ray (of the world, or of an entity: then voxel and normal
// are entity-local).
struct Hit {
    hit: bool,
    // The step budget ran out (counts as a miss).
    exhausted: bool,
    voxel: vec3<i32>,
    // Axis of the entry face (NO_AXIS: the origin was inside the voxel).
    axis: u32,
    // Entry-face normal (zero when the origin was inside).
    normal: vec3<i32>,
    // Time of entry, in units of the ray's |d|.
    t: f32,
    material: u32,
    steps: u32,
    // Entity id, or NO_ENTITY (generated in the prelude).
    entity: u32,
}

fn no_hit(steps: u32) -> Hit {
    return Hit(false, false, vec3<i32>(0), NO_AXIS, vec3<i32>(0), T_INF, 0u, steps, NO_ENTITY);
}

fn make_hit(r: Ray, cell: vec3<i32>, t: f32, axis: u32, material: u32, steps: u32) -> Hit {
    var n = vec3<i32>(0);
    if axis != NO_AXIS {
        n[axis] = select(1, -1, r.d[axis] > 0.0);
    }
    return Hit(true, false, cell, axis, n, t, material, steps, NO_ENTITY);
}

// One full trace: the world loop (traverse.wgsl or grid.wgsl) through the static world,
// then the instances whose world boxes the ray crosses before the world's hit or exit,
// found through their hierarchy (docs/NAADF.md §11): the GPU twin of
// world/src/traverse/entities.rs. Only the nearest entity hit (lowest id at equal times)
// survives, and only if it comes strictly before the world's hit or exit. Local instances
// (previews, markers: world/src/entity/local.rs) follow the world's records and carry the id
// NO_ENTITY, so their hits read as static geometry to everything that follows entity ids.

// How the world loop ended.
const END_HIT: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_EXHAUSTED: u32 = 3u;

struct WorldTrace {
    hit: Hit,
    end: u32,
    // When the ray entered the world, and when it hit or left it.
    t_entry: f32,
    t_end: f32,
}

// The end of a world loop whose step budget ran out at time \`t\` (entered at \`t_entry\`).
fn ran_out(t_entry: f32, t: f32) -> WorldTrace {
    var h = no_hit(world_info.max_steps);
    h.exhausted = true;
    return WorldTrace(h, END_EXHAUSTED, t_entry, t);
}

var<private> best_entity: Hit;
// The inverse rotation of \`best_entity\`'s instance.
var<private> best_rotation: vec4<f32>;
// Entity-grid cells visited (added to the step count of an entity hit).
var<private> entity_steps: u32;
// Whether the last \`trace\` returned an instance's hit (a local instance's has no entity id).
var<private> hit_instance: bool;

// Whether the world holds any instance. The host builds a pipeline for each value and
// picks the one that matches its world: a device that runs neighbouring rays in lock step
// may run code that no ray takes, and without instances none of the walk is compiled.
override HAS_INSTANCES: bool = true;

// How many instances the walk finds before it stops to test them.
const INSTANCE_BATCH: u32 = 8u;

// The walk's node stack and found instances, at module scope, so that an invocation holds
// (and zeroes) one of each rather than one for every trace inlined into it.
var<private> bvh_stack: array<u32, BVH_STACK>;
var<private> found_t: array<f32, INSTANCE_BATCH>;
var<private> found_slot: array<u32, INSTANCE_BATCH>;

// Walks the instance hierarchy (world/src/entity/bvh.rs: four-wide nodes of NODE_WORDS
// words, the children's f32 boxes axis by axis, then their references) and tests every
// instance whose box the ray is inside at some t in [t_lo, t_hi] (or up to the best entity
// hit so far). Boxes are padded and rounded outward, so the f32 test never rejects an
// instance the ray can hit. The walk gathers up to INSTANCE_BATCH instances, then tests them
// in the order the ray enters their boxes, stopping at a box that starts after the best hit,
// and goes on while nodes are left. Testing outside the walk's loop keeps that loop small,
// which is what costs on a device that runs neighbouring rays in lock step. With \`any_hit\`
// it returns at the first hit before \`t_hi\`.
fn find_instances(r: Ray, t_lo: f32, t_hi: f32, any_hit: bool) {
    // The world loop says whether its structure is traced with entities: the comparison
    // trees hold geometry only.
    if !TRACES_ENTITIES || !HAS_INSTANCES || world_info.instance_slots == 0u {
        return;
    }
    // 1/d, with ±FAR for axes the ray does not move along.
    let inv = select(1.0 / r.d, select(vec3<f32>(BVH_FAR), vec3<f32>(-BVH_FAR), r.d < vec3<f32>(0.0)), r.d == vec3<f32>(0.0));
    let o = vec3<f32>(r.o_int);
    bvh_stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        var far_limit = t_hi * 1.000001 + 1e-3;
        if best_entity.hit {
            far_limit = min(far_limit, best_entity.t * 1.000001 + 1e-3);
        }
        // A node adds at most four instances, so one is taken while four places are left.
        var found = 0u;
        while sp > 0u && found + 4u <= INSTANCE_BATCH {
            sp -= 1u;
            let base = bvh_stack[sp] * NODE_WORDS;
            // The four lanes at once, axis by axis.
            let tx0 = ((node_lanes(base) - o.x) - r.o_frac.x) * inv.x;
            let tx1 = ((node_lanes(base + 4u) - o.x) - r.o_frac.x) * inv.x;
            let ty0 = ((node_lanes(base + 8u) - o.y) - r.o_frac.y) * inv.y;
            let ty1 = ((node_lanes(base + 12u) - o.y) - r.o_frac.y) * inv.y;
            let tz0 = ((node_lanes(base + 16u) - o.z) - r.o_frac.z) * inv.z;
            let tz1 = ((node_lanes(base + 20u) - o.z) - r.o_frac.z) * inv.z;
            let near = max(vec4<f32>(t_lo - 1e-3), max(min(tx0, tx1), max(min(ty0, ty1), min(tz0, tz1))));
            let far = min(vec4<f32>(far_limit), min(max(tx0, tx1), min(max(ty0, ty1), max(tz0, tz1))));
            let child = vec4<u32>(hierarchy_word(base + 24u), hierarchy_word(base + 25u), hierarchy_word(base + 26u), hierarchy_word(base + 27u));
            let entered = !(near > far) & (child != vec4<u32>(BVH_NONE));
            // Each lane in turn: no loop, so that no lane's index is dynamic.
            if entered.x {
                keep_lane(child.x, near.x, &sp, &found);
            }
            if entered.y {
                keep_lane(child.y, near.y, &sp, &found);
            }
            if entered.z {
                keep_lane(child.z, near.z, &sp, &found);
            }
            if entered.w {
                keep_lane(child.w, near.w, &sp, &found);
            }
        }
        // Nearest box first, until one starts after the best hit (whose own box started no
        // later: the boxes are padded beyond the f32 test's rounding).
        for (var left = found; left > 0u; left--) {
            var k = 0u;
            for (var j = 1u; j < left; j++) {
                if found_t[j] < found_t[k] {
                    k = j;
                }
            }
            if best_entity.hit && found_t[k] > best_entity.t {
                break;
            }
            test_instance(r, found_slot[k] * RECORD_WORDS, t_lo);
            if any_hit && best_entity.hit && best_entity.t < t_hi {
                return;
            }
            found_t[k] = found_t[left - 1u];
            found_slot[k] = found_slot[left - 1u];
        }
    }
}

// Keeps a lane the ray enters at \`near\`: an instance among the found ones, or a node on the
// stack.
fn keep_lane(c: u32, near: f32, sp: ptr<function, u32>, found: ptr<function, u32>) {
    if (c & BVH_LEAF) != 0u {
        found_t[*found] = near;
        found_slot[*found] = c & ~BVH_LEAF;
        *found += 1u;
    } else if *sp < BVH_STACK {
        bvh_stack[*sp] = c;
        *sp += 1u;
    }
}

// Four lanes' planes of one axis, from word \`at\` of the hierarchy.
fn node_lanes(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4<u32>(hierarchy_word(at), hierarchy_word(at + 1u), hierarchy_word(at + 2u), hierarchy_word(at + 3u)));
}

// Decodes a smallest-three quaternion (world/src/entity/pack.rs).
fn decode_quat(w0: u32, w1: u32) -> vec4<f32> {
    let s = vec3<f32>(vec3<u32>(w0 & 0x3FFFu, (w0 >> 14u) & 0x3FFFu, (w0 >> 28u) | ((w1 & 0x3FFu) << 4u)));
    let small = (s - 8192.0) / 8192.0;
    let rest = sqrt(max(1.0 - dot(small, small), 0.0));
    let k = (w1 >> 10u) & 3u;
    if k == 0u {
        return vec4<f32>(rest, small.x, small.y, small.z);
    } else if k == 1u {
        return vec4<f32>(small.x, rest, small.y, small.z);
    } else if k == 2u {
        return vec4<f32>(small.x, small.y, rest, small.z);
    }
    return vec4<f32>(small, rest);
}

// Rotates \`v\` by the unit quaternion \`q = (x, y, z, w)\`.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// An instance record's position in 1/128 voxel (record words 0 and 1).
fn record_position(dx: u32, dy: u32) -> vec3<u32> {
    return vec3<u32>(dx & 0x1FFFFFu, (dx >> 21u) | (((dy >> 21u) & 0xFFu) << 11u), dy & 0x1FFFFFu);
}

// An instance record's entity id (record word 4).
fn record_id(e: u32) -> u32 {
    return e & 0x3FFFu;
}

// Tests the instance record at word \`at\` against the ray; keeps the nearest entity hit.
fn test_instance(r: Ray, at: u32, t_lo: f32) {
    let dx = instance_word(at);
    let dy = instance_word(at + 1u);
    let dz = instance_word(at + 2u);
    let dw = instance_word(at + 3u);
    let e = instance_word(at + 4u);
    let id = record_id(e);
    let size = vec3<u32>((e >> 14u) & 0x7Fu, (e >> 21u) & 0x7Fu, ((e >> 28u) & 0xFu) | (((dy >> 29u) & 7u) << 4u));
    let pos = record_position(dx, dy);
    var limit = T_INF;
    var equal_ok = false;
    if best_entity.hit {
        limit = best_entity.t;
        equal_ok = id < best_entity.entity;
    }
    // The entity lies within |size| of its local-origin corner: reject rays that pass
    // farther (with slack for f32), before transforming anything.
    let rel = vec3<f32>(r.o_int - vec3<i32>(pos >> vec3<u32>(7u))) + (r.o_frac - vec3<f32>(pos & vec3<u32>(127u)) / 128.0);
    let tc = -dot(rel, r.d) / (r.len * r.len);
    let radius = (length(vec3<f32>(size)) + 0.01) / r.len;
    let closest = rel + r.d * tc;
    if dot(closest, closest) > radius * radius * r.len * r.len || tc + radius < t_lo || tc - radius > limit {
        return;
    }
    let q = decode_quat(dz, dw & 0xFFFu);
    let local = ray_from(rotate(q, rel), rotate(q, r.d));
    let isize = vec3<i32>(size);
    let entry = ray_entry(local, isize);
    if !entry.ok {
        return;
    }
    let base = (dw >> 12u) * TYPE_ALIGN;
    var s = dda_start(local, entry);
    loop {
        entity_steps += 1u;
        if s.t > limit || (s.t == limit && !equal_ok) {
            return;
        }
        if s.t >= t_lo {
            let c = vec3<u32>(s.cell);
            let v = entity_type_word(base + c.x + size.x * (c.y + size.y * c.z));
            if (v & ENTITY_SOLID) != 0u {
                var h = make_hit(local, s.cell, s.t, s.axis, v & MAX_MATERIAL, 0u);
                h.entity = id;
                best_entity = h;
                best_rotation = q;
                return;
            }
        }
        dda_advance(local, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= isize) {
            return;
        }
    }
}

// The world-space normal of the hit the last \`trace\` returned (entity-local normals are
// rotated back to the world).
fn world_normal(h: Hit) -> vec3<f32> {
    let n = vec3<f32>(h.normal);
    if !hit_instance {
        return n;
    }
    return rotate(conjugate(best_rotation), n);
}

// Clears the entity state of the last trace and runs the world loop: how a trace starts.
fn world_first(r: Ray) -> WorldTrace {
    entity_steps = 0u;
    best_entity = no_hit(0u);
    hit_instance = false;
    return world_loop(r);
}

// Traces \`r\` through the world and its entities.
fn trace(r: Ray) -> Hit {
    let w = world_first(r);
    if w.end == END_MISSED || w.end == END_EXHAUSTED {
        return w.hit;
    }
    find_instances(r, w.t_entry, w.t_end, false);
    if best_entity.hit && best_entity.t < w.t_end {
        hit_instance = true;
        var h = best_entity;
        h.steps = w.hit.steps + entity_steps;
        return h;
    }
    var h = w.hit;
    h.steps += entity_steps;
    return h;
}

// Whether \`trace(r)\` would hit (\`x\`) and whether it would run out of steps (\`y\`), for rays
// that only ask whether something is in the way (shadow rays): a ray that hits the world
// needs no instance walk, and one that leaves it stops walking at the first instance hit.
fn occlusion(r: Ray) -> vec2<bool> {
    let w = world_first(r);
    if w.end != END_LEFT {
        return vec2<bool>(w.hit.hit, w.hit.exhausted);
    }
    find_instances(r, w.t_entry, w.t_end, true);
    return vec2<bool>(best_entity.hit && best_entity.t < w.t_end, false);
}

// The world loop over the chunk → block → voxel hierarchy (docs/NAADF.md §9), with
// AADF jumps (\`USE_AADF\`, the \`naadf\` method) or without (\`nodf\`): the GPU twin of
// world/src/traverse/hierarchy.rs. It sees the static world alone: entities are found
// afterwards, through their hierarchy (trace.wgsl).

override USE_AADF: bool = true;
// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;


fn to_edge(c: u32, neg: bool, edge: u32) -> i32 {
    let m = c & (edge - 1u);
    return i32(select(edge - 1u - m, m, neg));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing = vec3<u32>(0u, 2u, 4u) + select(vec3<u32>(0u), vec3<u32>(1u), r.d > vec3<f32>(0.0));
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(cell);
        let chunk = chunk_word(chunk_index(p >> vec3<u32>(4u), chunks));
        var skip = vec3<i32>(0);
        let cs = cell_state(chunk);
        if cs == STATE_FULL {
            return WorldTrace(make_hit(r, cell, t, axis, chunk & MAX_MATERIAL, steps), END_HIT, entry.t, t);
        } else if cs == STATE_EMPTY {
            for (var a = 0u; a < 3u; a++) {
                skip[a] = to_edge(p[a], neg[a], 16u);
                if USE_AADF {
                    skip[a] += 16 * i32(aadf_field(chunk, facing[a], CHUNK_FIELD_BITS));
                }
            }
        } else {
            let block = block_word((chunk & PAYLOAD) + index4((p >> vec3<u32>(2u)) & vec3<u32>(3u)));
            let bs = cell_state(block);
            if bs == STATE_FULL {
                return WorldTrace(make_hit(r, cell, t, axis, block & MAX_MATERIAL, steps), END_HIT, entry.t, t);
            } else if bs == STATE_EMPTY {
                for (var a = 0u; a < 3u; a++) {
                    skip[a] = to_edge(p[a], neg[a], 4u);
                    if USE_AADF {
                        skip[a] += 4 * i32(aadf_field(block, facing[a], CELL_FIELD_BITS));
                    }
                }
            } else {
                let v = group_voxel(block & PAYLOAD, index4(p & vec3<u32>(3u)));
                if (v & VOXEL_SOLID) != 0u {
                    return WorldTrace(make_hit(r, cell, t, axis, v & MAX_MATERIAL, steps), END_HIT, entry.t, t);
                }
                if USE_AADF {
                    for (var a = 0u; a < 3u; a++) {
                        skip[a] = i32(aadf_field(v, facing[a], CELL_FIELD_BITS));
                    }
                }
            }
        }
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            // An AADF box may reach beyond the world: the ray left it at the world's edge.
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, min(ex.t, leave_time(r, dims)));
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

// The samples of the lit passes: random streams (client/src/light/rng.rs), one per sample
// of each pixel, seeded from the run's seed, the pixel's index and the sample's number
// only; and the jittered camera ray of a sample.

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The stream of sample \`sample\` of pixel \`pixel\` under \`seed\`.
fn rng_new(seed: u32, pixel: u32, sample: u32) -> u32 {
    return pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(sample)));
}

// A uniform number in [0, 1) with 24 random bits.
fn rng_next(state: ptr<function, u32>) -> f32 {
    *state = pcg_hash(*state);
    return f32(*state >> 8u) * (1.0 / 16777216.0);
}

// The stream of sample \`sample\` of pixel \`pixel\`, after its first two draws: where in the
// pixel the sample's camera ray goes (uniform in [0, 1)²).
struct PixelStream {
    rng: u32,
    jitter: vec2<f32>,
}

fn pixel_stream(seed: u32, pixel: u32, sample: u32) -> PixelStream {
    var rng = rng_new(seed, pixel, sample);
    let jx = rng_next(&rng);
    let jy = rng_next(&rng);
    return PixelStream(rng, vec2<f32>(jx, jy));
}

// The camera's (unnormalised) direction through point \`jitter\` ([0, 1)²) of pixel \`gid\` of
// frame \`f\` (docs/CAMERA.md, with \`px + jitter.x\` for \`px + 0.5\`).
fn camera_dir(f: FrameInfo, gid: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let sx = 2.0 * (f32(gid.x) + jitter.x) / f32(f.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + jitter.y) / f32(f.height);
    return f.forward + sx * f.right + sy * f.up;
}

// The light model of the lit modes (docs/RENDERING.md §3a): the physical sky, the sun,
// BRDF sampling and one path's radiance. The GPU twin of client/src/light/ (sky.rs,
// scatter.rs, cpu.rs), written operation by operation like it so that the two path
// tracers agree up to rounding. Needs random.wgsl before it.
//
// The pass binds \`light: LightInfo\` (generated in the prelude from the Rust \`LightInfo\`),
// and declares \`DIFFUSE_TIER\` and \`diffuse_tier\` (no_tier.wgsl, or a lighting tier such as
// roma.wgsl) for \`path_step\`.

// PI, SURFACE_OFFSET (how far scattered and shadow rays start off the surface),
// MIN_ALPHA (the smallest GGX α a metal is traced with) and the physical sky's constants
// (PLANET_RADIUS, VIEW_STEPS, RAYLEIGH, MIE_G, OZONE, …) come from the prelude, generated
// from their Rust definitions in client/src/light/ (mod.rs, scatter.rs, sky.rs).

// ---- The physical sky (sky.rs) ----

// Distance from height \`h\` along zenith cosine \`mu\` to the sphere at height \`top\`; a
// negative value when it is not reached going forward.
fn sphere_distance(h: f32, mu: f32, top: f32) -> f32 {
    let r = PLANET_RADIUS + h;
    let disc = (top - h) * (2.0 * PLANET_RADIUS + top + h) + r * r * mu * mu;
    if disc < 0.0 {
        return -1.0;
    }
    let s = sqrt(disc);
    let far = -r * mu + s;
    if far < 0.0 {
        return -1.0;
    }
    let near = -r * mu - s;
    return select(far, near, near > 0.0);
}

struct Medium {
    sigma: vec3<f32>,
    rayleigh: f32,
    mie: f32,
}

fn medium(h: f32) -> Medium {
    let rayleigh = exp(-h / RAYLEIGH_SCALE);
    let mie = exp(-h / MIE_SCALE);
    let ozone = max(1.0 - abs(h - OZONE_CENTRE) / OZONE_HALF_WIDTH, 0.0);
    return Medium(RAYLEIGH * rayleigh + MIE_EXTINCTION * mie + OZONE * ozone, rayleigh, mie);
}

fn sun_transmittance(h: f32, mu: f32) -> vec3<f32> {
    if mu < 0.0 && sphere_distance(h, mu, 0.0) >= 0.0 {
        return vec3<f32>(0.0);
    }
    let length = max(sphere_distance(h, mu, ATMOSPHERE_HEIGHT), 0.0);
    let dt = length / f32(LIGHT_STEPS);
    let r = PLANET_RADIUS + h;
    var depth = vec3<f32>(0.0);
    for (var i = 0u; i < LIGHT_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let hi = sqrt(t * t + 2.0 * r * mu * t + r * r) - PLANET_RADIUS;
        depth += medium(hi).sigma * dt;
    }
    return exp(-depth);
}

// Sky radiance along unit \`dir\` for unit sun direction \`sun\`, per unit of irradiance.
fn sky_physical(dir: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let mu = dir.y;
    let nu = dot(dir, sun);
    let h0 = EYE_HEIGHT;
    let r0 = PLANET_RADIUS + h0;
    var length = sphere_distance(h0, mu, 0.0);
    if !(mu < 0.0 && length >= 0.0) {
        length = max(sphere_distance(h0, mu, ATMOSPHERE_HEIGHT), 0.0);
    }
    let dt = length / f32(VIEW_STEPS);
    let phase_r = 3.0 / (16.0 * PI) * (1.0 + nu * nu);
    let g2 = MIE_G * MIE_G;
    let phase_m = (1.0 - g2) / (4.0 * PI * pow(1.0 + g2 - 2.0 * MIE_G * nu, 1.5));
    var depth = vec3<f32>(0.0);
    var inscatter = vec3<f32>(0.0);
    for (var i = 0u; i < VIEW_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let r = sqrt(t * t + 2.0 * r0 * mu * t + r0 * r0);
        let h = r - PLANET_RADIUS;
        let mu_sun = (r0 * sun.y + t * nu) / r;
        let m = medium(h);
        let to_sun = sun_transmittance(h, mu_sun);
        let view = exp(-(depth + 0.5 * m.sigma * dt));
        let scatter = RAYLEIGH * m.rayleigh * phase_r + MIE_SCATTER * m.mie * phase_m;
        inscatter += view * to_sun * scatter * dt;
        depth += m.sigma * dt;
    }
    return inscatter;
}

// The sky along unit \`d\`, evaluated directly (no disc).
fn sky_direct(d: vec3<f32>) -> vec3<f32> {
    if light.sky_physical != 0u {
        return sky_physical(d, light.sun_dir) * light.sky;
    }
    return light.sky;
}

// The sky along unit \`d\`; with \`disc\`, the sun's disc too. \`sky_base(d)\` is the including
// pass's choice: \`sky_direct\` (the path tracer) or the atmosphere table (\`gi\`).
fn sky_radiance(d: vec3<f32>, disc: bool) -> vec3<f32> {
    var l = sky_base(d);
    if disc {
        l += sun_disc(d);
    }
    return l;
}

// The sun's disc along unit \`d\` (0 off the disc, or with the sun off).
fn sun_disc(d: vec3<f32>) -> vec3<f32> {
    if light.sun_on != 0u && 1.0 - dot(d, light.sun_dir) <= light.sun_omc {
        return vec3<f32>(light.sun_disc);
    }
    return vec3<f32>(0.0);
}

// ---- Scattering (scatter.rs) ----

struct Basis {
    t: vec3<f32>,
    b: vec3<f32>,
}

fn basis(n: vec3<f32>) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

fn sample_cosine(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let f = basis(n);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (r * cos(phi)) + f.b * (r * sin(phi)) + n * sqrt(max(1.0 - u.x, 0.0)));
}

fn sample_cone(axis: vec3<f32>, omc: f32, u: vec2<f32>) -> vec3<f32> {
    let f = basis(axis);
    let x = u.x * omc;
    let c = 1.0 - x;
    let s = sqrt(max(x * (2.0 - x), 0.0));
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (s * cos(phi)) + f.b * (s * sin(phi)) + axis * c);
}

fn schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let k = 1.0 - clamp(c, 0.0, 1.0);
    let k2 = k * k;
    return f0 + (vec3<f32>(1.0) - f0) * (k2 * k2 * k);
}

fn smith_lambda(alpha: f32, c: f32) -> f32 {
    let c2 = max(c * c, 1e-12);
    let tan2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (-1.0 + sqrt(1.0 + alpha * alpha * tan2));
}

fn ggx_d(alpha: f32, c: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = c * c * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

fn ggx(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, alpha: f32, f0: vec3<f32>) -> vec3<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if co <= 0.0 || ci <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = normalize(wo + wi);
    let g2 = 1.0 / (1.0 + smith_lambda(alpha, co) + smith_lambda(alpha, ci));
    return schlick(f0, dot(wo, h)) * (ggx_d(alpha, dot(n, h)) * g2 / (4.0 * co * ci));
}

struct Scattered {
    dir: vec3<f32>,
    weight: vec3<f32>,
}

fn ggx_sample(n: vec3<f32>, wo: vec3<f32>, alpha: f32, f0: vec3<f32>, u: vec2<f32>) -> Scattered {
    let f = basis(n);
    let v = vec3<f32>(dot(wo, f.t), dot(wo, f.b), dot(wo, n));
    let vh = normalize(vec3<f32>(alpha * v.x, alpha * v.y, v.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = t1 * p1 + t2 * p2 + vh * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    let m = normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    let lwi = m * (2.0 * dot(v, m)) - v;
    let wi = normalize(f.t * lwi.x + f.b * lwi.y + n * lwi.z);
    let lo = smith_lambda(alpha, v.z);
    let li = smith_lambda(alpha, lwi.z);
    return Scattered(wi, schlick(f0, dot(v, m)) * ((1.0 + lo) / (1.0 + lo + li)));
}

// ---- Paths (cpu.rs) ----

// Whether a shadow ray meets anything before leaving the world (a ray out of cells counts
// as blocked).
fn blocked(r: Ray, p: vec3<f32>, dir: vec3<f32>) -> bool {
    return any(occlusion(ray_at(r, p, dir)));
}

// One sample of the sun's disc seen from \`p\` (relative to \`r\`'s integer origin, just off a
// surface of normal \`n\`): its direction, and the irradiance it brings (\`E·cosθ\`-weighted)
// when it is above the surface and unblocked, else 0. Two random numbers are drawn
// whenever the sun is on (cpu.rs \`sun_sample\`).
struct SunSample {
    dir: vec3<f32>,
    irradiance: f32,
}

fn sun_sample(r: Ray, p: vec3<f32>, n: vec3<f32>, rng: ptr<function, u32>) -> SunSample {
    if light.sun_on == 0u {
        return SunSample(vec3<f32>(0.0), 0.0);
    }
    let u = vec2<f32>(rng_next(rng), rng_next(rng));
    let wi = sample_cone(light.sun_dir, light.sun_omc, u);
    let c = dot(n, wi);
    if c > 0.0 && !blocked(r, p, wi) {
        return SunSample(wi, c * light.sun_weight);
    }
    return SunSample(wi, 0.0);
}

// One step of a path: what it adds and whether it goes on.
struct PathState {
    r: Ray,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    sees_disc: bool,
    alive: bool,
    // The normal of the first surface met (zero until then).
    first_normal: vec3<f32>,
}

// Follows the path in \`s\` to its next surface: adds the light found there and, when
// \`scatter\`, picks the next ray (or ends the path). Returns the distance to the surface
// (−1 when the ray found none).
fn path_step(s: ptr<function, PathState>, scatter: bool, rng: ptr<function, u32>) -> f32 {
    let r = (*s).r;
    let h = trace(r);
    let d = r.d / r.len;
    (*s).alive = false;
    if h.exhausted {
        return -1.0;
    }
    if !h.hit {
        (*s).radiance += (*s).throughput * sky_radiance(d, (*s).sees_disc);
        return -1.0;
    }
    let distance = h.t * r.len;
    if h.axis == NO_AXIS {
        return distance;
    }
    // Before any other trace: world_normal reads the last trace's entity rotation.
    let n = world_normal(h);
    if all((*s).first_normal == vec3<f32>(0.0)) {
        (*s).first_normal = n;
    }
    let m = material(h.material);
    if m.kind == KIND_EMISSIVE {
        (*s).radiance += (*s).throughput * m.albedo * m.emission;
    }
    // A lighting tier (\`roma\`, \`irradiance\`) lights diffuse and emissive surfaces itself,
    // and the path ends there; mirrors and metals scatter on.
    if DIFFUSE_TIER && m.kind != KIND_MIRROR && m.kind != KIND_METAL {
        let surface = vec3<f32>(r.o_int) + ray_local(r, h.t);
        (*s).radiance += (*s).throughput * diffuse_tier(h, surface, n, m.albedo, rng);
        return distance;
    }
    if !scatter {
        return distance;
    }
    let p = ray_local(r, h.t) + n * SURFACE_OFFSET;
    var next: Scattered;
    if m.kind == KIND_MIRROR {
        (*s).sees_disc = true;
        next = Scattered(d - n * (2.0 * dot(d, n)), m.albedo);
    } else {
        let wo = -d;
        let alpha = max(m.roughness, MIN_ALPHA);
        let sun = sun_sample(r, p, n, rng);
        if sun.irradiance > 0.0 {
            var f = m.albedo / PI;
            if m.kind == KIND_METAL {
                f = ggx(n, wo, sun.dir, alpha, m.albedo);
            }
            (*s).radiance += (*s).throughput * f * sun.irradiance;
        }
        let u = vec2<f32>(rng_next(rng), rng_next(rng));
        (*s).sees_disc = false;
        if m.kind == KIND_METAL {
            next = ggx_sample(n, wo, alpha, m.albedo, u);
        } else {
            next = Scattered(sample_cosine(n, u), m.albedo);
        }
    }
    if dot(next.dir, n) > 0.0 {
        (*s).throughput *= next.weight;
        (*s).r = ray_at(r, p, next.dir);
        (*s).alive = true;
    }
    return distance;
}

// One path: the radiance it brought back, the distance from its origin to the first
// surface (−1 for the sky) and that surface's normal.
struct PathSample {
    radiance: vec3<f32>,
    distance: f32,
    normal: vec3<f32>,
}

// The radiance arriving along \`primary\` when the path may scatter \`bounces\` more times,
// drawing from \`rng\`. \`sees_disc\`: whether the ray sees the sun's disc (camera and mirror
// rays do; rays scattered by other surfaces get the sun by next-event estimation instead).
fn path_radiance(primary: Ray, bounces: u32, sees_disc: bool, rng: ptr<function, u32>) -> PathSample {
    var s = PathState(primary, vec3<f32>(0.0), vec3<f32>(1.0), sees_disc, true, vec3<f32>(0.0));
    let distance = path_step(&s, bounces > 0u, rng);
    for (var bounce = 1u; bounce <= bounces && s.alive; bounce++) {
        path_step(&s, bounce < bounces, rng);
    }
    return PathSample(s.radiance, distance, s.first_normal);
}

// No lighting tier: \`path_step\` (light.wgsl) traces diffuse surfaces as the light model
// does. Included by the path tracer, the GI passes and the irradiance cache's updates;
// \`roma\` and \`irradiance\` include roma.wgsl and irradiance.wgsl instead.

const DIFFUSE_TIER: bool = false;

fn diffuse_tier(h: Hit, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// Passes \`path_trace\` (progressive path tracing, \`pathtrace\`) and \`path_sample\` (one sample
// per pixel per frame, \`baseline\`), one invocation per pixel (docs/RENDERING.md §3a, §3b).
//
// \`path_trace\`: each dispatch adds sample number \`frame.sample\` to every pixel's running
// sum; the host divides by the count. A sample's random stream depends only on (seed, pixel, sample
// number), and every pixel adds its samples in number order, so the sums are the same bit
// for bit however the dispatches are grouped into submissions.
//
// One sample per dispatch, not a loop over samples: lavapipe (Mesa 22.3) miscompiles a
// sample loop around the bounce loop around the traversal loop, and pixels silently lose
// samples.
//
// \`FrameInfo\` and \`LightInfo\` are generated in the prelude from their Rust twins.

@group(1) @binding(0) var<uniform> frame: FrameInfo;
@group(1) @binding(1) var<uniform> light: LightInfo;
// \`path_trace\`: running sums (RGB, count). \`path_sample\`: this frame's sample (RGB, and
// the distance to the first surface, −1 for the sky).
@group(1) @binding(2) var<storage, read_write> radiance: array<vec4<f32>>;

// The path tracer sees the sky as the light model defines it, direction by direction.
fn sky_base(d: vec3<f32>) -> vec3<f32> {
    return sky_direct(d);
}

// Sample \`frame.sample\` of pixel \`gid\`.
fn pixel_sample(gid: vec2<u32>) -> PathSample {
    let stream = pixel_stream(frame.seed, gid.x + gid.y * frame.width, frame.sample);
    var rng = stream.rng;
    let r = ray_new(frame.cam_int, frame.cam_frac, camera_dir(frame, gid, stream.jitter));
    return path_radiance(r, light.bounces, true, &rng);
}

@compute @workgroup_size(8, 8)
fn path_trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let s = pixel_sample(gid.xy);
    radiance[gid.x + gid.y * frame.width] += vec4<f32>(s.radiance, 1.0);
}

@compute @workgroup_size(8, 8)
fn path_sample(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let s = pixel_sample(gid.xy);
    radiance[gid.x + gid.y * frame.width] = vec4<f32>(s.radiance, s.distance);
}

`,Zs=`// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the
// Rust code, the world's storage bindings.
struct WorldInfo {
    // World size in voxels.
    size: vec3<u32>,
    // Slots of the instance buffer on the device, the world's and then the local
    // instances' (records of 5 words; 0: no instance to trace).
    instance_slots: u32,
    // World size in chunks.
    chunks: vec3<u32>,
    // Cells a ray may visit before it counts as a miss.
    max_steps: u32,
}
@group(0) @binding(0) var<uniform> world_info: WorldInfo;
struct FrameInfo {
    // Camera position, integer part (floor).
    cam_int: vec3<i32>,
    // Image width in pixels.
    width: u32,
    // Camera position, fractional part in [0, 1).
    cam_frac: vec3<f32>,
    // Image height in pixels.
    height: u32,
    // View direction.
    forward: vec3<f32>,
    // The run's seed.
    seed: u32,
    // Image right, scaled by a·W/H.
    right: vec3<f32>,
    // Number of the sample this dispatch adds.
    sample: u32,
    // Image up, scaled by a.
    up: vec3<f32>,
    // 1 when a temporal pass has a history to blend with (0 for the path tracer).
    history: u32,
}
struct LightInfo {
    // Uniform sky: its radiance. Physical sky: the irradiance of the sun lighting it.
    sky: vec3<f32>,
    // 1 for the physical sky.
    sky_physical: u32,
    // Unit vector toward the sun (the sun lighting the physical sky when it is off).
    sun_dir: vec3<f32>,
    // 1 when the sun shines (its disc and its samples).
    sun_on: u32,
    // The disc's radiance.
    sun_disc: f32,
    // The weight of one disc sample: radiance times solid angle.
    sun_weight: f32,
    // 1 − cos of the disc's angular radius.
    sun_omc: f32,
    // Scattered rays after the camera ray.
    bounces: u32,
}
struct GiInfo {
    // Frames rendered in this history before this one.
    frame: u32,
    // The long-term TAA slot this frame writes (\`frame % TAA_SLOTS\`).
    taa_slot: u32,
    // Earlier frames the TAA may read (at most \`TAA_SLOTS − 1\`).
    taa_valid: u32,
    // The first frame rendered after the newest change of the materials, or of more
    // chunks than are marked one by one (0: none): the near-change rule everywhere.
    edit_frame: u32,
    // The first frame rendered after the newest change of any chunk, entity moves
    // included (0: none): the still path keeps no sample from before it.
    change_frame: u32,
    // This frame's jitter in the pixel, x (a point of a 32-point (0, 5, 2)-net).
    jitter_x: f32,
    // This frame's jitter in the pixel, y.
    jitter_y: f32,
    // 8×8 regions across.
    regions_x: u32,
    // 8×8 regions down.
    regions_y: u32,
    // Samples the sample ring holds.
    ring_capacity: u32,
    // 1 when the bilateral denoiser runs.
    denoise: u32,
    // Where each pixel's own secondary sample starts in \`mem\` (tagged with the
    // frame that traced it).
    off_own: u32,
    // Where the atmosphere table starts in \`mem\` (vec4 words; the cameras start at 0).
    off_lut: u32,
    // Where the first-hit surfaces start in \`mem\`.
    off_gbuf: u32,
    // Where the first-hit materials start in \`mem\`.
    off_gmat: u32,
    // Where the first-hit light starts in \`mem\`.
    off_emitted: u32,
    // Where the TAA's per-pixel sums and ranges start in \`mem\`.
    off_taa_info: u32,
    // Where the incoming light starts in \`mem\`.
    off_illum: u32,
    // Where the denoiser's intermediate starts in \`mem\`.
    off_illum2: u32,
    // Where the results start in \`mem\`.
    off_result: u32,
    // Where the refined samples start in \`mem\`.
    off_refined: u32,
    // Where the regions' statistics start in \`mem\`.
    off_region_info: u32,
    // Where the sample ring starts in \`mem\`.
    off_ring: u32,
    // Where the queued pixels start in \`words\`.
    off_queue_list: u32,
}
const STATE_SHIFT: u32 = 30u;
const STATE_EMPTY: u32 = 0u;
const STATE_FULL: u32 = 1u;
const STATE_MIXED: u32 = 2u;
const PAYLOAD: u32 = 1073741823u;
const MAX_MATERIAL: u32 = 32767u;
const VOXEL_SOLID: u32 = 32768u;
const CHUNK_FIELD_BITS: u32 = 5u;
const CELL_FIELD_BITS: u32 = 2u;
const KIND_DIFFUSE: u32 = 0u;
const KIND_EMISSIVE: u32 = 1u;
const KIND_METAL: u32 = 2u;
const KIND_MIRROR: u32 = 3u;
const ENTITY_SOLID: u32 = 2147483648u;
const TYPE_ALIGN: u32 = 64u;
const RECORD_WORDS: u32 = 5u;
const NO_ENTITY: u32 = 16383u;
const NODE_WORDS: u32 = 28u;
const BVH_STACK: u32 = 64u;
const BVH_LEAF: u32 = 2147483648u;
const BVH_NONE: u32 = 4294967295u;
const BVH_FAR: f32 = 1e30f;
const SURFACE_OFFSET: f32 = 0.01f;
const MIN_ALPHA: f32 = 0.001f;
const PI: f32 = 3.1415927f;
const PLANET_RADIUS: f32 = 6360000.0f;
const ATMOSPHERE_HEIGHT: f32 = 60000.0f;
const EYE_HEIGHT: f32 = 100.0f;
const VIEW_STEPS: u32 = 24u;
const LIGHT_STEPS: u32 = 6u;
const RAYLEIGH: vec3<f32> = vec3<f32>(5.802e-6f, 1.3558e-5f, 3.31e-5f);
const RAYLEIGH_SCALE: f32 = 8000.0f;
const MIE_SCATTER: f32 = 3.996e-6f;
const MIE_EXTINCTION: f32 = 4.44e-6f;
const MIE_SCALE: f32 = 1200.0f;
const MIE_G: f32 = 0.8f;
const OZONE: vec3<f32> = vec3<f32>(6.5e-7f, 1.881e-6f, 8.5e-8f);
const OZONE_CENTRE: f32 = 25000.0f;
const OZONE_HALF_WIDTH: f32 = 15000.0f;
// The first word of each buffer in \`world\`.
struct WorldOffsets {
    chunks: u32,
    blocks: u32,
    voxels: u32,
    materials: u32,
    entity_types: u32,
    entity_instances: u32,
    entity_hierarchy: u32,
    structure: u32,
}
@group(0) @binding(1) var<uniform> world_offsets: WorldOffsets;
@group(0) @binding(2) var<storage, read> world: array<u32>;
fn chunk_word(i: u32) -> u32 { return world[world_offsets.chunks + i]; }
fn block_word(i: u32) -> u32 { return world[world_offsets.blocks + i]; }
fn voxel_word(i: u32) -> u32 { return world[world_offsets.voxels + i]; }
fn material_word(i: u32) -> u32 { return world[world_offsets.materials + i]; }
fn entity_type_word(i: u32) -> u32 { return world[world_offsets.entity_types + i]; }
fn instance_word(i: u32) -> u32 { return world[world_offsets.entity_instances + i]; }
fn hierarchy_word(i: u32) -> u32 { return world[world_offsets.entity_hierarchy + i]; }
fn structure_word(i: u32) -> u32 { return world[world_offsets.structure + i]; }

// The world buffers (docs/FORMAT.md §5) and how to read their cells.
//
// Generated by naadf-client (client/src/gpu/shaders.rs) from the Rust definitions, in the
// prelude before this file:
// - the parameters \`world_info: WorldInfo\` (size in voxels and chunks, the instance
//   buffer's slots, the step budget);
// - the constants of the cell layout (STATE_*, PAYLOAD, MAX_MATERIAL, VOXEL_SOLID,
//   CHUNK_FIELD_BITS, CELL_FIELD_BITS), the material kinds (KIND_*), the entity layout
//   (ENTITY_SOLID, TYPE_ALIGN, RECORD_WORDS, NO_ENTITY), the instance hierarchy's (NODE_WORDS,
//   BVH_*) and the frame modes (MODE_*);
// - the storage bindings and the accessors \`chunk_word\`, \`block_word\`, \`voxel_word\`,
//   \`material_word\`, \`entity_type_word\`, \`instance_word\`, \`hierarchy_word\` (and
//   \`structure_word\` for the comparison traversals): a buffer larger than the adapter's
//   storage-binding limit is split across several bindings, and the accessor picks the
//   part.

// State of a chunk or block cell: STATE_EMPTY, STATE_FULL or (also for state 3)
// STATE_MIXED.
fn cell_state(c: u32) -> u32 {
    return min(c >> STATE_SHIFT, STATE_MIXED);
}

// Field \`dir\` (order −x, +x, −y, +y, −z, +z) of a packed AADF.
fn aadf_field(word: u32, dir: u32, bits: u32) -> u32 {
    return (word >> (bits * dir)) & ((1u << bits) - 1u);
}

// The index of chunk \`c\` in a world of \`chunks\` chunks (\`world_info.chunks\`). Loops read
// \`world_info\` once before they start and pass its fields: it is a storage buffer, and a
// storage read in every step is a bounds-checked load on lavapipe.
fn chunk_index(c: vec3<u32>, chunks: vec3<u32>) -> u32 {
    return c.x + chunks.x * (c.y + chunks.y * c.z);
}

fn index4(p: vec3<u32>) -> u32 {
    return p.x + 4u * p.y + 16u * p.z;
}

// Voxel \`i\` (0..64) of the voxel group starting at word \`ptr\`.
fn group_voxel(ptr: u32, i: u32) -> u32 {
    return (voxel_word(ptr + i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

// A material's entry (docs/FORMAT.md §5.4).
struct Material {
    kind: u32,
    albedo: vec3<f32>,
    emission: f32,
    roughness: f32,
}

fn material(id: u32) -> Material {
    let w0 = material_word(4u * id);
    let w1 = material_word(4u * id + 1u);
    let w2 = material_word(4u * id + 2u);
    let rg = unpack2x16float(w1);
    let be = unpack2x16float(w2);
    return Material(w0 & 3u, vec3<f32>(rg.x, rg.y, be.x), be.y, unpack2x16float(w0).y);
}

// Rays and the event model every traversal shares (world/src/traverse/ray.rs, in f32).
//
// A ray keeps its origin split into an integer part \`o_int\` and a fraction \`o_frac\` in [0, 1)
// (docs/NAADF.md §9), so precision does not depend on where in the world it starts.
// The direction \`d\` is kept exactly as given (not renormalised, which would move the line
// by an f32 rounding): times are in units of |d| and the ray's \`len\` converts them to
// distances. Every decision compares plane-crossing times from the one function \`t_at\`,
// so the traversal is a consistent walk of the event order "(t, axis), x before y before
// z at equal t"; it departs from the CPU's f64 order only where two crossings are within
// f32 rounding of each other.

// A cell bound beyond any world for unconstrained axes (the CPU walk uses 2^40, which no
// i32 holds).
const FAR_CELL: i32 = 1073741824;
const T_INF: f32 = 3.0e38;
const NO_AXIS: u32 = 3u;

struct Ray {
    o_int: vec3<i32>,
    o_frac: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    len: f32,
}

fn ray_new(o_int: vec3<i32>, o_frac: vec3<f32>, d: vec3<f32>) -> Ray {
    // The inverse of a zero component is never read: such axes never cross a plane.
    let safe = select(vec3<f32>(1.0), d, d != vec3<f32>(0.0));
    return Ray(o_int, o_frac, d, 1.0 / safe, length(d));
}

// A ray from an unsplit origin.
fn ray_from(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(o);
    return ray_new(vec3<i32>(fl), min(o - fl, vec3<f32>(0.99999994)), d);
}

// The ray's point at time \`t\`, relative to its integer origin.
fn ray_local(r: Ray, t: f32) -> vec3<f32> {
    return r.o_frac + r.d * t;
}

// A ray starting at \`p\` (relative to \`r\`'s integer origin) along \`d\`.
fn ray_at(r: Ray, p: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(p);
    return ray_new(r.o_int + vec3<i32>(fl), min(p - fl, vec3<f32>(0.99999994)), d);
}

// Time at which the ray crosses plane \`k\` of \`axis\`.
fn t_at(r: Ray, a: u32, k: i32) -> f32 {
    return (f32(k - r.o_int[a]) - r.o_frac[a]) * r.inv[a];
}

// Whether the crossing of plane \`k\` of axis \`b\` comes before the event \`(t, a)\`.
fn crossed(r: Ray, b: u32, k: i32, t: f32, a: u32) -> bool {
    let tb = t_at(r, b, k);
    return tb < t || (tb == t && b < a);
}

// The cell of axis \`b\` right after event \`(t, a)\`, known to lie in \`lo..=hi\`.
fn cell_after(r: Ray, b: u32, t: f32, a: u32, lo: i32, hi: i32) -> i32 {
    let d = r.d[b];
    if lo == hi || d == 0.0 {
        return lo;
    }
    let p = r.o_frac[b] + d * t;
    let fl = floor(p);
    var k = clamp(i32(fl) + r.o_int[b], lo, hi);
    let f = p - fl;
    // Far from a plane the floor is certain; near one, decide by crossing times.
    let tol = 4e-6 * (abs(d * t) + 1.0);
    if f > tol && f < 1.0 - tol {
        return k;
    }
    if d > 0.0 {
        while k < hi && crossed(r, b, k + 1, t, a) {
            k += 1;
        }
        while k > lo && !crossed(r, b, k, t, a) {
            k -= 1;
        }
    } else {
        while k > lo && crossed(r, b, k, t, a) {
            k -= 1;
        }
        while k < hi && !crossed(r, b, k + 1, t, a) {
            k += 1;
        }
    }
    return k;
}

// Where a ray begins inside the box [0, size): its first cell, the time it is entered and
// the axis whose plane it crossed (NO_AXIS when the origin is inside). \`ok\` is false when
// the ray misses the box.
struct Entry {
    cell: vec3<i32>,
    t: f32,
    axis: u32,
    ok: bool,
}

fn ray_entry(r: Ray, size: vec3<i32>) -> Entry {
    let start = r.o_int;
    var miss = Entry(vec3<i32>(0), 0.0, NO_AXIS, false);
    if all(start >= vec3<i32>(0)) && all(start < size) {
        return Entry(start, 0.0, NO_AXIS, true);
    }
    // The last slab-entry event, in (t, axis) order.
    var bt = 0.0;
    var ba = NO_AXIS;
    for (var a = 0u; a < 3u; a++) {
        var plane: i32;
        if start[a] < 0 {
            if r.d[a] <= 0.0 {
                return miss;
            }
            plane = 0;
        } else if start[a] >= size[a] {
            if r.d[a] >= 0.0 {
                return miss;
            }
            plane = size[a];
        } else {
            continue;
        }
        let t = t_at(r, a, plane);
        if ba == NO_AXIS || t >= bt {
            bt = t;
            ba = a;
        }
    }
    var cell = vec3<i32>(0);
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            cell[b] = select(size[b] - 1, 0, r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            cell[b] = cell_after(r, b, bt, ba, start[b], FAR_CELL);
        } else if r.d[b] < 0.0 {
            cell[b] = cell_after(r, b, bt, ba, -FAR_CELL, start[b]);
        } else {
            cell[b] = start[b];
        }
    }
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return miss;
    }
    return Entry(cell, bt, ba, true);
}

// When a ray inside the box [0, size] leaves it: the first crossing of a far plane it moves
// toward (world/src/traverse/ray.rs \`leave_time\`).
fn leave_time(r: Ray, size: vec3<i32>) -> f32 {
    var t = T_INF;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            t = min(t, t_at(r, a, select(0, size[a], r.d[a] > 0.0)));
        }
    }
    return t;
}

// Leaving the empty cuboid made of \`cell\` extended by \`skip\` cells toward the ray on each
// axis: the exit event and the cell entered by it.
struct Exit {
    t: f32,
    axis: u32,
    next: vec3<i32>,
}

fn ray_exit(r: Ray, cell: vec3<i32>, skip: vec3<i32>) -> Exit {
    var bound = vec3<i32>(0);
    var bt = T_INF;
    var ba = 0u;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] == 0.0 {
            continue;
        }
        bound[a] = select(cell[a] - skip[a], cell[a] + 1 + skip[a], r.d[a] > 0.0);
        let t = t_at(r, a, bound[a]);
        if t < bt {
            bt = t;
            ba = a;
        }
    }
    var next = cell;
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            next[b] = select(bound[b] - 1, bound[b], r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b], cell[b] + skip[b]);
        } else if r.d[b] < 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b] - skip[b], cell[b]);
        }
    }
    return Exit(bt, ba, next);
}

// Amanatides–Woo state in the same event order (ties step the lowest axis first).
struct Dda {
    cell: vec3<i32>,
    tmax: vec3<f32>,
    t: f32,
    axis: u32,
}

fn dda_start(r: Ray, e: Entry) -> Dda {
    var tmax = vec3<f32>(T_INF);
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            tmax[a] = t_at(r, a, select(e.cell[a], e.cell[a] + 1, r.d[a] > 0.0));
        }
    }
    return Dda(e.cell, tmax, e.t, e.axis);
}

fn dda_advance(r: Ray, s: ptr<function, Dda>) {
    var a = 0u;
    if (*s).tmax[1] < (*s).tmax[a] {
        a = 1u;
    }
    if (*s).tmax[2] < (*s).tmax[a] {
        a = 2u;
    }
    (*s).t = (*s).tmax[a];
    let c = (*s).cell[a] + select(-1, 1, r.d[a] > 0.0);
    (*s).cell[a] = c;
    (*s).axis = a;
    (*s).tmax[a] = t_at(r, a, select(c, c + 1, r.d[a] > 0.0));
}

// The first solid voxel along a ray (of the world, or of an entity: then voxel and normal
// are entity-local).
struct Hit {
    hit: bool,
    // The step budget ran out (counts as a miss).
    exhausted: bool,
    voxel: vec3<i32>,
    // Axis of the entry face (NO_AXIS: the origin was inside the voxel).
    axis: u32,
    // Entry-face normal (zero when the origin was inside).
    normal: vec3<i32>,
    // Time of entry, in units of the ray's |d|.
    t: f32,
    material: u32,
    steps: u32,
    // Entity id, or NO_ENTITY (generated in the prelude).
    entity: u32,
}

fn no_hit(steps: u32) -> Hit {
    return Hit(false, false, vec3<i32>(0), NO_AXIS, vec3<i32>(0), T_INF, 0u, steps, NO_ENTITY);
}

fn make_hit(r: Ray, cell: vec3<i32>, t: f32, axis: u32, material: u32, steps: u32) -> Hit {
    var n = vec3<i32>(0);
    if axis != NO_AXIS {
        n[axis] = select(1, -1, r.d[axis] > 0.0);
    }
    return Hit(true, false, cell, axis, n, t, material, steps, NO_ENTITY);
}

// One full trace: the world loop (traverse.wgsl or grid.wgsl) through the static world,
// then the instances whose world boxes the ray crosses before the world's hit or exit,
// found through their hierarchy (docs/NAADF.md §11): the GPU twin of
// world/src/traverse/entities.rs. Only the nearest entity hit (lowest id at equal times)
// survives, and only if it comes strictly before the world's hit or exit. Local instances
// (previews, markers: world/src/entity/local.rs) follow the world's records and carry the id
// NO_ENTITY, so their hits read as static geometry to everything that follows entity ids.

// How the world loop ended.
const END_HIT: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_EXHAUSTED: u32 = 3u;

struct WorldTrace {
    hit: Hit,
    end: u32,
    // When the ray entered the world, and when it hit or left it.
    t_entry: f32,
    t_end: f32,
}

// The end of a world loop whose step budget ran out at time \`t\` (entered at \`t_entry\`).
fn ran_out(t_entry: f32, t: f32) -> WorldTrace {
    var h = no_hit(world_info.max_steps);
    h.exhausted = true;
    return WorldTrace(h, END_EXHAUSTED, t_entry, t);
}

var<private> best_entity: Hit;
// The inverse rotation of \`best_entity\`'s instance.
var<private> best_rotation: vec4<f32>;
// Entity-grid cells visited (added to the step count of an entity hit).
var<private> entity_steps: u32;
// Whether the last \`trace\` returned an instance's hit (a local instance's has no entity id).
var<private> hit_instance: bool;

// Whether the world holds any instance. The host builds a pipeline for each value and
// picks the one that matches its world: a device that runs neighbouring rays in lock step
// may run code that no ray takes, and without instances none of the walk is compiled.
override HAS_INSTANCES: bool = true;

// How many instances the walk finds before it stops to test them.
const INSTANCE_BATCH: u32 = 8u;

// The walk's node stack and found instances, at module scope, so that an invocation holds
// (and zeroes) one of each rather than one for every trace inlined into it.
var<private> bvh_stack: array<u32, BVH_STACK>;
var<private> found_t: array<f32, INSTANCE_BATCH>;
var<private> found_slot: array<u32, INSTANCE_BATCH>;

// Walks the instance hierarchy (world/src/entity/bvh.rs: four-wide nodes of NODE_WORDS
// words, the children's f32 boxes axis by axis, then their references) and tests every
// instance whose box the ray is inside at some t in [t_lo, t_hi] (or up to the best entity
// hit so far). Boxes are padded and rounded outward, so the f32 test never rejects an
// instance the ray can hit. The walk gathers up to INSTANCE_BATCH instances, then tests them
// in the order the ray enters their boxes, stopping at a box that starts after the best hit,
// and goes on while nodes are left. Testing outside the walk's loop keeps that loop small,
// which is what costs on a device that runs neighbouring rays in lock step. With \`any_hit\`
// it returns at the first hit before \`t_hi\`.
fn find_instances(r: Ray, t_lo: f32, t_hi: f32, any_hit: bool) {
    // The world loop says whether its structure is traced with entities: the comparison
    // trees hold geometry only.
    if !TRACES_ENTITIES || !HAS_INSTANCES || world_info.instance_slots == 0u {
        return;
    }
    // 1/d, with ±FAR for axes the ray does not move along.
    let inv = select(1.0 / r.d, select(vec3<f32>(BVH_FAR), vec3<f32>(-BVH_FAR), r.d < vec3<f32>(0.0)), r.d == vec3<f32>(0.0));
    let o = vec3<f32>(r.o_int);
    bvh_stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        var far_limit = t_hi * 1.000001 + 1e-3;
        if best_entity.hit {
            far_limit = min(far_limit, best_entity.t * 1.000001 + 1e-3);
        }
        // A node adds at most four instances, so one is taken while four places are left.
        var found = 0u;
        while sp > 0u && found + 4u <= INSTANCE_BATCH {
            sp -= 1u;
            let base = bvh_stack[sp] * NODE_WORDS;
            // The four lanes at once, axis by axis.
            let tx0 = ((node_lanes(base) - o.x) - r.o_frac.x) * inv.x;
            let tx1 = ((node_lanes(base + 4u) - o.x) - r.o_frac.x) * inv.x;
            let ty0 = ((node_lanes(base + 8u) - o.y) - r.o_frac.y) * inv.y;
            let ty1 = ((node_lanes(base + 12u) - o.y) - r.o_frac.y) * inv.y;
            let tz0 = ((node_lanes(base + 16u) - o.z) - r.o_frac.z) * inv.z;
            let tz1 = ((node_lanes(base + 20u) - o.z) - r.o_frac.z) * inv.z;
            let near = max(vec4<f32>(t_lo - 1e-3), max(min(tx0, tx1), max(min(ty0, ty1), min(tz0, tz1))));
            let far = min(vec4<f32>(far_limit), min(max(tx0, tx1), min(max(ty0, ty1), max(tz0, tz1))));
            let child = vec4<u32>(hierarchy_word(base + 24u), hierarchy_word(base + 25u), hierarchy_word(base + 26u), hierarchy_word(base + 27u));
            let entered = !(near > far) & (child != vec4<u32>(BVH_NONE));
            // Each lane in turn: no loop, so that no lane's index is dynamic.
            if entered.x {
                keep_lane(child.x, near.x, &sp, &found);
            }
            if entered.y {
                keep_lane(child.y, near.y, &sp, &found);
            }
            if entered.z {
                keep_lane(child.z, near.z, &sp, &found);
            }
            if entered.w {
                keep_lane(child.w, near.w, &sp, &found);
            }
        }
        // Nearest box first, until one starts after the best hit (whose own box started no
        // later: the boxes are padded beyond the f32 test's rounding).
        for (var left = found; left > 0u; left--) {
            var k = 0u;
            for (var j = 1u; j < left; j++) {
                if found_t[j] < found_t[k] {
                    k = j;
                }
            }
            if best_entity.hit && found_t[k] > best_entity.t {
                break;
            }
            test_instance(r, found_slot[k] * RECORD_WORDS, t_lo);
            if any_hit && best_entity.hit && best_entity.t < t_hi {
                return;
            }
            found_t[k] = found_t[left - 1u];
            found_slot[k] = found_slot[left - 1u];
        }
    }
}

// Keeps a lane the ray enters at \`near\`: an instance among the found ones, or a node on the
// stack.
fn keep_lane(c: u32, near: f32, sp: ptr<function, u32>, found: ptr<function, u32>) {
    if (c & BVH_LEAF) != 0u {
        found_t[*found] = near;
        found_slot[*found] = c & ~BVH_LEAF;
        *found += 1u;
    } else if *sp < BVH_STACK {
        bvh_stack[*sp] = c;
        *sp += 1u;
    }
}

// Four lanes' planes of one axis, from word \`at\` of the hierarchy.
fn node_lanes(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4<u32>(hierarchy_word(at), hierarchy_word(at + 1u), hierarchy_word(at + 2u), hierarchy_word(at + 3u)));
}

// Decodes a smallest-three quaternion (world/src/entity/pack.rs).
fn decode_quat(w0: u32, w1: u32) -> vec4<f32> {
    let s = vec3<f32>(vec3<u32>(w0 & 0x3FFFu, (w0 >> 14u) & 0x3FFFu, (w0 >> 28u) | ((w1 & 0x3FFu) << 4u)));
    let small = (s - 8192.0) / 8192.0;
    let rest = sqrt(max(1.0 - dot(small, small), 0.0));
    let k = (w1 >> 10u) & 3u;
    if k == 0u {
        return vec4<f32>(rest, small.x, small.y, small.z);
    } else if k == 1u {
        return vec4<f32>(small.x, rest, small.y, small.z);
    } else if k == 2u {
        return vec4<f32>(small.x, small.y, rest, small.z);
    }
    return vec4<f32>(small, rest);
}

// Rotates \`v\` by the unit quaternion \`q = (x, y, z, w)\`.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// An instance record's position in 1/128 voxel (record words 0 and 1).
fn record_position(dx: u32, dy: u32) -> vec3<u32> {
    return vec3<u32>(dx & 0x1FFFFFu, (dx >> 21u) | (((dy >> 21u) & 0xFFu) << 11u), dy & 0x1FFFFFu);
}

// An instance record's entity id (record word 4).
fn record_id(e: u32) -> u32 {
    return e & 0x3FFFu;
}

// Tests the instance record at word \`at\` against the ray; keeps the nearest entity hit.
fn test_instance(r: Ray, at: u32, t_lo: f32) {
    let dx = instance_word(at);
    let dy = instance_word(at + 1u);
    let dz = instance_word(at + 2u);
    let dw = instance_word(at + 3u);
    let e = instance_word(at + 4u);
    let id = record_id(e);
    let size = vec3<u32>((e >> 14u) & 0x7Fu, (e >> 21u) & 0x7Fu, ((e >> 28u) & 0xFu) | (((dy >> 29u) & 7u) << 4u));
    let pos = record_position(dx, dy);
    var limit = T_INF;
    var equal_ok = false;
    if best_entity.hit {
        limit = best_entity.t;
        equal_ok = id < best_entity.entity;
    }
    // The entity lies within |size| of its local-origin corner: reject rays that pass
    // farther (with slack for f32), before transforming anything.
    let rel = vec3<f32>(r.o_int - vec3<i32>(pos >> vec3<u32>(7u))) + (r.o_frac - vec3<f32>(pos & vec3<u32>(127u)) / 128.0);
    let tc = -dot(rel, r.d) / (r.len * r.len);
    let radius = (length(vec3<f32>(size)) + 0.01) / r.len;
    let closest = rel + r.d * tc;
    if dot(closest, closest) > radius * radius * r.len * r.len || tc + radius < t_lo || tc - radius > limit {
        return;
    }
    let q = decode_quat(dz, dw & 0xFFFu);
    let local = ray_from(rotate(q, rel), rotate(q, r.d));
    let isize = vec3<i32>(size);
    let entry = ray_entry(local, isize);
    if !entry.ok {
        return;
    }
    let base = (dw >> 12u) * TYPE_ALIGN;
    var s = dda_start(local, entry);
    loop {
        entity_steps += 1u;
        if s.t > limit || (s.t == limit && !equal_ok) {
            return;
        }
        if s.t >= t_lo {
            let c = vec3<u32>(s.cell);
            let v = entity_type_word(base + c.x + size.x * (c.y + size.y * c.z));
            if (v & ENTITY_SOLID) != 0u {
                var h = make_hit(local, s.cell, s.t, s.axis, v & MAX_MATERIAL, 0u);
                h.entity = id;
                best_entity = h;
                best_rotation = q;
                return;
            }
        }
        dda_advance(local, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= isize) {
            return;
        }
    }
}

// The world-space normal of the hit the last \`trace\` returned (entity-local normals are
// rotated back to the world).
fn world_normal(h: Hit) -> vec3<f32> {
    let n = vec3<f32>(h.normal);
    if !hit_instance {
        return n;
    }
    return rotate(conjugate(best_rotation), n);
}

// Clears the entity state of the last trace and runs the world loop: how a trace starts.
fn world_first(r: Ray) -> WorldTrace {
    entity_steps = 0u;
    best_entity = no_hit(0u);
    hit_instance = false;
    return world_loop(r);
}

// Traces \`r\` through the world and its entities.
fn trace(r: Ray) -> Hit {
    let w = world_first(r);
    if w.end == END_MISSED || w.end == END_EXHAUSTED {
        return w.hit;
    }
    find_instances(r, w.t_entry, w.t_end, false);
    if best_entity.hit && best_entity.t < w.t_end {
        hit_instance = true;
        var h = best_entity;
        h.steps = w.hit.steps + entity_steps;
        return h;
    }
    var h = w.hit;
    h.steps += entity_steps;
    return h;
}

// Whether \`trace(r)\` would hit (\`x\`) and whether it would run out of steps (\`y\`), for rays
// that only ask whether something is in the way (shadow rays): a ray that hits the world
// needs no instance walk, and one that leaves it stops walking at the first instance hit.
fn occlusion(r: Ray) -> vec2<bool> {
    let w = world_first(r);
    if w.end != END_LEFT {
        return vec2<bool>(w.hit.hit, w.hit.exhausted);
    }
    find_instances(r, w.t_entry, w.t_end, true);
    return vec2<bool>(best_entity.hit && best_entity.t < w.t_end, false);
}

// The world loop over the chunk → block → voxel hierarchy (docs/NAADF.md §9), with
// AADF jumps (\`USE_AADF\`, the \`naadf\` method) or without (\`nodf\`): the GPU twin of
// world/src/traverse/hierarchy.rs. It sees the static world alone: entities are found
// afterwards, through their hierarchy (trace.wgsl).

override USE_AADF: bool = true;
// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;


fn to_edge(c: u32, neg: bool, edge: u32) -> i32 {
    let m = c & (edge - 1u);
    return i32(select(edge - 1u - m, m, neg));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing = vec3<u32>(0u, 2u, 4u) + select(vec3<u32>(0u), vec3<u32>(1u), r.d > vec3<f32>(0.0));
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(cell);
        let chunk = chunk_word(chunk_index(p >> vec3<u32>(4u), chunks));
        var skip = vec3<i32>(0);
        let cs = cell_state(chunk);
        if cs == STATE_FULL {
            return WorldTrace(make_hit(r, cell, t, axis, chunk & MAX_MATERIAL, steps), END_HIT, entry.t, t);
        } else if cs == STATE_EMPTY {
            for (var a = 0u; a < 3u; a++) {
                skip[a] = to_edge(p[a], neg[a], 16u);
                if USE_AADF {
                    skip[a] += 16 * i32(aadf_field(chunk, facing[a], CHUNK_FIELD_BITS));
                }
            }
        } else {
            let block = block_word((chunk & PAYLOAD) + index4((p >> vec3<u32>(2u)) & vec3<u32>(3u)));
            let bs = cell_state(block);
            if bs == STATE_FULL {
                return WorldTrace(make_hit(r, cell, t, axis, block & MAX_MATERIAL, steps), END_HIT, entry.t, t);
            } else if bs == STATE_EMPTY {
                for (var a = 0u; a < 3u; a++) {
                    skip[a] = to_edge(p[a], neg[a], 4u);
                    if USE_AADF {
                        skip[a] += 4 * i32(aadf_field(block, facing[a], CELL_FIELD_BITS));
                    }
                }
            } else {
                let v = group_voxel(block & PAYLOAD, index4(p & vec3<u32>(3u)));
                if (v & VOXEL_SOLID) != 0u {
                    return WorldTrace(make_hit(r, cell, t, axis, v & MAX_MATERIAL, steps), END_HIT, entry.t, t);
                }
                if USE_AADF {
                    for (var a = 0u; a < 3u; a++) {
                        skip[a] = i32(aadf_field(v, facing[a], CELL_FIELD_BITS));
                    }
                }
            }
        }
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            // An AADF box may reach beyond the world: the ray left it at the world's edge.
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, min(ex.t, leave_time(r, dims)));
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

// The first-hit chain shared by \`albedo\` (render.wgsl) and \`gi\` (gi_primary.wgsl): a camera
// ray followed through up to MAX_SEGMENTS − 1 mirror bounces to the first surface that is
// not a mirror, with the bounce planes of the reference's first-hit record
// (docs/RENDERING.md §2, §3c).

// Hit-plane sentinels of the first-hit record (docs/NAADF.md §10).
const HIT_NOTHING: u32 = 0x1FFFFu;
const HIT_UNDEFINED: u32 = 0u;
// Mirror segments a path may follow (the primary segment included).
const MAX_SEGMENTS: u32 = 4u;
// Secondary-ray origins start SURFACE_OFFSET off the surface, along its normal
// (docs/NAADF.md §12; from the prelude).

// How a chain ended.
const CHAIN_SURFACE: u32 = 0u;
const CHAIN_SKY: u32 = 1u;
// The last segment allowed met a mirror too.
const CHAIN_LIMIT: u32 = 2u;

// The 17-bit hit plane: normal id (1 −x, 2 +x, 3 −y, 4 +y, 5 −z, 6 +z; 7 = origin inside
// the voxel) in bits 0–2, the plane's integer coordinate in bits 3–16.
fn encode_plane(h: Hit) -> u32 {
    if h.axis == NO_AXIS {
        return 7u;
    }
    let positive = h.normal[h.axis] > 0;
    let id = 2u * h.axis + select(1u, 2u, positive);
    let coord = u32(h.voxel[h.axis] + select(0, 1, positive)) & 0x3FFFu;
    return id | (coord << 3u);
}

struct Chain {
    // The last segment and what it met (\`h.hit\` is false for the sky).
    r: Ray,
    h: Hit,
    // The final surface's world normal (read right after its trace: world_normal reads the
    // entity rotation of the last trace).
    n: vec3<f32>,
    // The product of the mirror weights along the chain.
    throughput: vec3<f32>,
    planes: array<u32, 4>,
    // Path length to the final surface; −1 for the sky and the mirror limit.
    distance: f32,
    end: u32,
}

// Follows \`primary\` (whose first hit is \`first\`) through mirrors. A mirror weighs the path
// by Schlick's Fresnel with F0 = albedo when \`schlick\`, by its albedo otherwise (the light
// model's tinted mirror, docs/RENDERING.md §3a).
fn first_hit_chain(primary: Ray, first: Hit, schlick: bool) -> Chain {
    var c = Chain(primary, first, vec3<f32>(0.0), vec3<f32>(1.0),
        array<u32, 4>(HIT_UNDEFINED, HIT_UNDEFINED, HIT_UNDEFINED, HIT_UNDEFINED), 0.0, CHAIN_SURFACE);
    for (var seg = 0u; seg < MAX_SEGMENTS; seg++) {
        if seg > 0u {
            c.h = trace(c.r);
        }
        let dn = c.r.d / c.r.len;
        if !c.h.hit {
            c.planes[seg] = HIT_NOTHING;
            c.distance = -1.0;
            c.end = CHAIN_SKY;
            return c;
        }
        c.planes[seg] = encode_plane(c.h);
        c.distance += c.h.t * c.r.len;
        c.n = world_normal(c.h);
        let m = material(c.h.material);
        if m.kind != KIND_MIRROR {
            return c;
        }
        if seg + 1u == MAX_SEGMENTS {
            c.planes[seg] = HIT_NOTHING;
            c.distance = -1.0;
            c.end = CHAIN_LIMIT;
            return c;
        }
        if schlick {
            let cos_i = clamp(-dot(c.n, dn), 0.0, 1.0);
            c.throughput *= m.albedo + (1.0 - m.albedo) * pow(1.0 - cos_i, 5.0);
        } else {
            c.throughput *= m.albedo;
        }
        let p = ray_local(c.r, c.h.t) + c.n * SURFACE_OFFSET;
        c.r = ray_at(c.r, p, reflect(dn, c.n));
    }
    return c;
}

// Pass: render one frame, one invocation per pixel (docs/RENDERING.md).
//
// Camera rays follow the camera contract (docs/CAMERA.md): the host passes the camera position
// split into integer and fraction, \`forward\`, and \`right\`/\`up\` already scaled by
// a·W/H and a (a = tan(fov_y/2)), so that dir = forward + sx·right + sy·up with
// sx = 2(px + 0.5)/W − 1 and sy = 1 − 2(py + 0.5)/H.
//
// Modes (MODE_*, generated after the pass from the client's \`Mode\`): albedo, material,
// normal, steps. Every pixel becomes one RGBA8 word; with bit 0 of \`flags\`, the pixel's
// first-hit record (the reference's \`firstHitData\`) is written to \`gbuffer\` as well.

// \`View\` is generated after the pass from its Rust definition (client/src/gpu/params.rs).

@group(1) @binding(0) var<uniform> view: View;
@group(1) @binding(1) var<storage, read_write> pixels: array<u32>;
@group(1) @binding(2) var<storage, read_write> gbuffer: array<vec4<u32>>;

const SUN_COLOR: vec3<f32> = vec3<f32>(1.0, 0.96, 0.88);
// Cosine of the sun disc's angular radius (about 1.8°).
const SUN_DISC_COS: f32 = 0.9995;

fn srgb(c: vec3<f32>) -> vec3<f32> {
    let x = clamp(c, vec3<f32>(0.0), vec3<f32>(1.0));
    return select(1.055 * pow(x, vec3<f32>(1.0 / 2.4)) - 0.055, 12.92 * x, x <= vec3<f32>(0.0031308));
}

fn pack_rgb(c: vec3<f32>) -> u32 {
    let b = vec3<u32>(floor(clamp(c, vec3<f32>(0.0), vec3<f32>(1.0)) * 255.0 + 0.5));
    return b.x | (b.y << 8u) | (b.z << 16u) | 0xFF000000u;
}

// The sky: a vertical gradient plus the sun disc.
fn sky(d: vec3<f32>) -> vec3<f32> {
    let horizon = vec3<f32>(0.70, 0.80, 0.95);
    var c: vec3<f32>;
    if d.y >= 0.0 {
        c = mix(horizon, vec3<f32>(0.20, 0.40, 0.80), sqrt(d.y));
    } else {
        c = mix(horizon, vec3<f32>(0.30, 0.28, 0.25), sqrt(-d.y));
    }
    if dot(d, view.sun) > SUN_DISC_COS {
        c += 8.0 * SUN_COLOR;
    }
    return c;
}

// ACES filmic fit (Narkowicz 2015).
fn tone_map(c: vec3<f32>) -> vec3<f32> {
    return clamp((c * (2.51 * c + 0.03)) / (c * (2.43 * c + 0.59) + 0.14), vec3<f32>(0.0), vec3<f32>(1.0));
}

// Step-count heat map: blue → cyan → green → yellow → red over [0, 1].
fn heat(v: f32) -> vec3<f32> {
    let x = clamp(v, 0.0, 1.0) * 4.0;
    return clamp(vec3<f32>(x - 2.0, select(x, 4.0 - x, x > 3.0), 2.0 - x), vec3<f32>(0.0), vec3<f32>(1.0));
}

// Follows the primary hit through up to MAX_SEGMENTS − 1 mirror bounces and shades the
// first non-mirror surface: albedo × (hard sun shadow + ambient) + emission, Schlick
// weights on mirrors, the sky on a miss. Returns the colour and writes the first-hit
// record.
fn shade_path(primary: Ray, first: Hit, gb: ptr<function, vec4<u32>>) -> vec3<f32> {
    let c = first_hit_chain(primary, first, true);
    var light = vec3<f32>(0.0);
    var kind = KIND_DIFFUSE;
    var mat_id = 0u;
    var entity = NO_ENTITY;
    if c.end == CHAIN_SKY {
        light = c.throughput * sky(c.r.d / c.r.len);
    } else if c.end == CHAIN_SURFACE {
        let m = material(c.h.material);
        kind = m.kind;
        mat_id = c.h.material;
        entity = c.h.entity;
        let p = ray_local(c.r, c.h.t) + c.n * SURFACE_OFFSET;
        let lit = select(1.0, 0.0, occlusion(ray_at(c.r, p, view.sun)).x);
        let direct = 2.0 * max(dot(c.n, view.sun), 0.0) * lit;
        let ambient = 0.2 * max(dot(view.sun, normalize(c.n + 1.01 * view.sun)), 0.0);
        var col = m.albedo * (direct + ambient) * SUN_COLOR;
        if m.kind == KIND_EMISSIVE {
            col += m.albedo * m.emission;
        }
        light = c.throughput * col;
    }
    let dist_bits = pack2x16float(vec2<f32>(c.distance, 0.0)) & 0x7FFFu;
    *gb = vec4<u32>(
        entity | (c.planes[0] << 15u),
        select(0u, 1u, kind != KIND_METAL) | (c.planes[1] << 15u),
        mat_id | (c.planes[2] << 15u),
        dist_bits | (c.planes[3] << 15u),
    );
    return light;
}

@compute @workgroup_size(8, 8)
fn render(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= view.width || gid.y >= view.height {
        return;
    }
    let sx = 2.0 * (f32(gid.x) + 0.5) / f32(view.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + 0.5) / f32(view.height);
    let r = ray_new(view.cam_oi, view.cam_of, view.forward + sx * view.right + sy * view.up);
    let h = trace(r);
    // The diagnostic colour comes first: world_normal reads the entity rotation of the
    // last trace, which shade_path's shadow and mirror traces overwrite.
    var color = vec3<f32>(0.0);
    if view.mode == MODE_MATERIAL {
        color = select(vec3<f32>(0.0), srgb(material(h.material).albedo), h.hit);
    } else if view.mode == MODE_NORMAL {
        color = select(vec3<f32>(0.0), world_normal(h) * 0.5 + 0.5, h.hit);
    } else if view.mode == MODE_STEPS {
        color = heat(log2(1.0 + f32(h.steps)) * view.steps_scale);
    }
    var gb = vec4<u32>(0u);
    if view.mode == MODE_ALBEDO || (view.flags & 1u) != 0u {
        let shaded = srgb(tone_map(shade_path(r, h, &gb)));
        if view.mode == MODE_ALBEDO {
            color = shaded;
        }
    }
    let i = gid.x + gid.y * view.width;
    pixels[i] = pack_rgb(color);
    if (view.flags & 1u) != 0u {
        gbuffer[i] = gb;
    }
}

struct View {
    // Camera position, integer part (floor).
    cam_oi: vec3<i32>,
    // The mode's code (\`MODE_*\`).
    mode: u32,
    // Camera position, fractional part in [0, 1).
    cam_of: vec3<f32>,
    // Image width in pixels.
    width: u32,
    // View direction.
    forward: vec3<f32>,
    // Image height in pixels.
    height: u32,
    // Image right, scaled by a·W/H.
    right: vec3<f32>,
    // Bit 0: write each pixel's first-hit record.
    flags: u32,
    // Image up, scaled by a.
    up: vec3<f32>,
    // \`1 / log2(1 + STEPS_FULL_SCALE)\`: the heat map's scale.
    steps_scale: f32,
    // Unit vector toward the sun.
    sun: vec3<f32>,
    // Padding to 16 bytes.
    _pad: u32,
}
const MODE_ALBEDO: u32 = 0u;
const MODE_MATERIAL: u32 = 1u;
const MODE_NORMAL: u32 = 2u;
const MODE_STEPS: u32 = 3u;
`,Qs=[{name:`chunks`,id:0},{name:`blocks`,id:2},{name:`voxels`,id:3},{name:`materials`,id:4},{name:`entity_types`,id:6},{name:`entity_instances`,id:7}],$s={size:32,fields:{size:{offset:0,type:`vec3<u32>`},instance_slots:{offset:12,type:`u32`},chunks:{offset:16,type:`vec3<u32>`},max_steps:{offset:28,type:`u32`}}},ec={size:96,fields:{cam_oi:{offset:0,type:`vec3<i32>`},mode:{offset:12,type:`u32`},cam_of:{offset:16,type:`vec3<f32>`},width:{offset:28,type:`u32`},forward:{offset:32,type:`vec3<f32>`},height:{offset:44,type:`u32`},right:{offset:48,type:`vec3<f32>`},flags:{offset:60,type:`u32`},up:{offset:64,type:`vec3<f32>`},steps_scale:{offset:76,type:`f32`},sun:{offset:80,type:`vec3<f32>`},_pad:{offset:92,type:`u32`}}},tc={size:80,fields:{cam_int:{offset:0,type:`vec3<i32>`},width:{offset:12,type:`u32`},cam_frac:{offset:16,type:`vec3<f32>`},height:{offset:28,type:`u32`},forward:{offset:32,type:`vec3<f32>`},seed:{offset:44,type:`u32`},right:{offset:48,type:`vec3<f32>`},sample:{offset:60,type:`u32`},up:{offset:64,type:`vec3<f32>`},history:{offset:76,type:`u32`}}},nc={size:48,fields:{sky:{offset:0,type:`vec3<f32>`},sky_physical:{offset:12,type:`u32`},sun_dir:{offset:16,type:`vec3<f32>`},sun_on:{offset:28,type:`u32`},sun_disc:{offset:32,type:`f32`},sun_weight:{offset:36,type:`f32`},sun_omc:{offset:40,type:`f32`},bounces:{offset:44,type:`u32`}}},rc={size:96,fields:{frame:{offset:0,type:`u32`},taa_slot:{offset:4,type:`u32`},taa_valid:{offset:8,type:`u32`},edit_frame:{offset:12,type:`u32`},change_frame:{offset:16,type:`u32`},jitter_x:{offset:20,type:`f32`},jitter_y:{offset:24,type:`f32`},regions_x:{offset:28,type:`u32`},regions_y:{offset:32,type:`u32`},ring_capacity:{offset:36,type:`u32`},denoise:{offset:40,type:`u32`},off_own:{offset:44,type:`u32`},off_lut:{offset:48,type:`u32`},off_gbuf:{offset:52,type:`u32`},off_gmat:{offset:56,type:`u32`},off_emitted:{offset:60,type:`u32`},off_taa_info:{offset:64,type:`u32`},off_illum:{offset:68,type:`u32`},off_illum2:{offset:72,type:`u32`},off_result:{offset:76,type:`u32`},off_refined:{offset:80,type:`u32`},off_region_info:{offset:84,type:`u32`},off_ring:{offset:88,type:`u32`},off_queue_list:{offset:92,type:`u32`}}},ic={size:32,fields:{camera:{offset:0,type:`vec3<f32>`},ao_range:{offset:12,type:`f32`},side:{offset:16,type:`u32`},directions:{offset:20,type:`u32`},_pad0:{offset:24,type:`u32`},_pad1:{offset:28,type:`u32`}}},ac={size:64,fields:{t:{offset:0,type:`vec3<f32>`},cell:{offset:12,type:`f32`},b:{offset:16,type:`vec3<f32>`},first_tile:{offset:28,type:`u32`},w:{offset:32,type:`vec3<f32>`},offset:{offset:44,type:`f32`},base:{offset:48,type:`vec3<i32>`},_pad:{offset:60,type:`u32`}}},oc={size:32,fields:{tile:{offset:0,type:`vec3<i32>`},window:{offset:12,type:`u32`},clear:{offset:16,type:`u32`},_pad0:{offset:20,type:`u32`},_pad1:{offset:24,type:`u32`},_pad2:{offset:28,type:`u32`}}},sc={size:32,fields:{stamp:{offset:0,type:`u32`},mask:{offset:4,type:`u32`},max_requests:{offset:8,type:`u32`},budget:{offset:12,type:`u32`},seed:{offset:16,type:`u32`},boxes:{offset:20,type:`u32`},_pad0:{offset:24,type:`u32`},_pad1:{offset:28,type:`u32`}}},cc=[0x40400000,0x40400000,0x40400000,1,0xbf400000,0x3f000000,0x3eddb3d7,1,0x4727fa5d,0x40400046,926566462,8],lc=[0x40400000,0x40400000,0x40400000,1,0xbf400000,0x3f000000,0x3eddb3d7,1,0x4727fa5d,0x40400046,926566462,3],uc={albedo:0,material:1,normal:2,steps:3},dc=[-.75,.5,.4330127],fc=65536,pc=[`gi_atmosphere`,`gi_first_hit`,`gi_poses`,`gi_taa`,`gi_queue`,`gi_queue_scan`,`gi_trace`,`gi_project`,`gi_project_store`,`gi_refine`,`gi_resample`,`gi_denoise_x`,`gi_denoise_y`,`gi_merge`],K={TAA_SLOTS:32,CONTROL_WORDS:144,CAMERA_HISTORY:128,LUT_SIZE:256,BUCKET_SLOTS:32,MAX_KEPT:7,QUEUE_PERIOD:2,RING_VEC4:3,EDIT_HISTORY_FRAMES:8,CONTROL_TRACE_ARGS:0,CONTROL_PROJECT_ARGS:4,CAM_WORDS:5,CONTROL_QUEUED:8,CONTROL_START:9,CONTROL_VALID:10,CONTROL_HEAD:11,CONTROL_FRAMES:16,TAA_PIXEL_BYTES:256,RING_PER_PIXEL:2,POSE_TABLE_WORDS:2097024,CHANGE_REACH:2,MAX_LOCAL_CHANGES:4096,ARGS_BYTES:32,NO_ENTITY:16383},q={NODE_WORDS:28,LEAF:0x80000000,NONE:0xffffffff,FAR:1e30,BOUNDS_PAD:.015625,F32_PAD:.015625,BINS:16,SAH_DEPTH:24,REFIT_SLACK:1.25},mc={SOLID:0x80000000,TYPE_ALIGN:64,RECORD_WORDS:5,LOCAL_ID:16383,IDENTITY_ROTATION:[0x8002000,3584]},J={LEVELS:3,TILE:32,TILE_WORDS:1024,WINDOW_TILES:8,CELL:[1,4,16],OFFSET:[1,2,2],REACH:94,DIRECTIONS:16,SIDE:4,AO_RANGE:32,FRAMES:[[.8162161205656171,.22921877001854332,-.5303300858899107,-.22921877001854332,-.7141139653242934,-.6614378277661477,-.5303300858899107,.6614378277661477,-.5303300858899106],[.9781492776181497,.07445559421202184,-.19411428382689055,-.07445559421202184,-.7462950920986515,-.6614378277661476,-.19411428382689055,.6614378277661476,-.7244443697168013],[.9781492776181497,-.07445559421202182,.19411428382689047,.07445559421202182,-.7462950920986515,-.6614378277661476,.19411428382689047,.6614378277661476,-.7244443697168013],[.8162161205656173,-.2292187700185432,.5303300858899106,.2292187700185432,-.7141139653242936,-.6614378277661476,.5303300858899106,.6614378277661476,-.5303300858899107],[.5604946260818231,.4012806116909011,-.7244443697168013,-.4012806116909011,-.6336196577450675,-.6614378277661476,-.7244443697168013,.6614378277661476,-.19411428382689055],[.973444409525698,.14545095930644542,-.1767766952966369,-.14545095930644542,-.20333228577093887,-.9682458365518543,-.1767766952966369,.9682458365518543,-.17677669529663687],[.973444409525698,-.1454509593064454,.17677669529663687,.1454509593064454,-.20333228577093887,-.9682458365518543,.17677669529663687,.9682458365518543,-.1767766952966369],[.5604946260818231,-.4012806116909011,.7244443697168013,.4012806116909011,-.6336196577450675,-.6614378277661476,.7244443697168013,.6614378277661476,-.19411428382689055],[.5604946260818231,.4012806116909011,.7244443697168013,.4012806116909011,.6336196577450675,-.6614378277661476,-.7244443697168013,.6614378277661476,.19411428382689055],[.973444409525698,.1454509593064454,.17677669529663687,.1454509593064454,.20333228577093887,-.9682458365518543,-.17677669529663687,.9682458365518543,.1767766952966369],[.973444409525698,-.14545095930644542,-.1767766952966369,-.14545095930644542,.20333228577093887,-.9682458365518543,.1767766952966369,.9682458365518543,.17677669529663687],[.5604946260818231,-.4012806116909011,-.7244443697168013,-.4012806116909011,.6336196577450675,-.6614378277661476,.7244443697168013,.6614378277661476,.19411428382689055],[.8162161205656173,.2292187700185432,.5303300858899106,.2292187700185432,.7141139653242936,-.6614378277661476,-.5303300858899106,.6614378277661476,.5303300858899107],[.9781492776181497,.07445559421202182,.19411428382689047,.07445559421202182,.7462950920986515,-.6614378277661476,-.19411428382689047,.6614378277661476,.7244443697168013],[.9781492776181497,-.07445559421202184,-.19411428382689055,-.07445559421202184,.7462950920986515,-.6614378277661476,.19411428382689055,.6614378277661476,.7244443697168013],[.8162161205656171,-.22921877001854332,-.5303300858899107,-.22921877001854332,.7141139653242934,-.6614378277661477,.5303300858899107,.6614378277661477,.5303300858899106],[.6074703320792287,.2616864452805141,.75,.2616864452805141,.8255423698129906,-.49999999999999994,-.75,.49999999999999994,.43301270189221946]]},Y={WORDS:8,LIST:4,COUNT:0,FRESH:1,TAKEN:2,OCCUPIED:3,HISTORY:64,BOUNCE_DISTANCE:32,MIN_SLOTS:1048576,MAX_BOXES:256,MAX_REQUESTS:4194240,DEFAULT_RAYS:262144,RAYS_PER_SAMPLE_SUN:4,RAYS_PER_SAMPLE:2};function hc(e,t,n,r){return JSON.stringify([e,t,n,r.generation])}function gc(e,t){let n=new ArrayBuffer(e.size),r=new DataView(n);for(let[n,i]of Object.entries(t)){let t=e.fields[n];if(!t)throw Error(`no field ${n}`);(Array.isArray(i)?i:[i]).forEach((e,n)=>{let i=t.offset+4*n;t.type.includes(`f32`)?r.setFloat32(i,e,!0):t.type.includes(`i32`)?r.setInt32(i,e,!0):r.setUint32(i,e,!0)})}return n}var _c=(e,t)=>({binding:e,visibility:GPUShaderStage.COMPUTE,buffer:{type:t}}),vc=class{device;layout;group;layoutGeneration=-1;constructor(e){this.device=e,this.layout=e.createBindGroupLayout({entries:[_c(0,`uniform`),_c(1,`uniform`),_c(2,`read-only-storage`)]})}of(e){return this.group&&this.layoutGeneration===e.layoutGeneration||(this.group=this.device.createBindGroup({layout:this.layout,entries:[{binding:0,resource:{buffer:e.info}},{binding:1,resource:{buffer:e.offsets}},{binding:2,resource:{buffer:e.buffer}}]}),this.layoutGeneration=e.layoutGeneration),this.group}};function yc(e,t){let n=new Map,r=i=>{let a=n.get(i);if(!a){let o={...t.compute.constants,HAS_INSTANCES:+!!i};a=e.createComputePipelineAsync({...t,compute:{...t.compute,constants:o}}),n.set(i,a),a.then(()=>r(!i)).catch(()=>void 0)}return a};return r}function bc(e,t,n,r,i,a){let o=e.createBindGroupLayout({entries:a.map((e,t)=>_c(t,e))});return{pipeline:yc(e,{layout:e.createPipelineLayout({bindGroupLayouts:[t.layout,o]}),compute:{module:e.createShaderModule({label:n,code:r}),entryPoint:i}}),layout:o}}function xc(e,t,n){return e.createBindGroup({layout:t,entries:n.map((e,t)=>({binding:t,resource:{buffer:e}}))})}async function Sc(e,t,n,r,i){let a=e.createCommandEncoder(),o=a.beginComputePass();o.setPipeline(await t),o.setBindGroup(0,n),o.setBindGroup(1,r);let s=e.limits.maxComputeWorkgroupsPerDimension;o.dispatchWorkgroups(Math.min(i,s),Math.ceil(i/s)),o.end(),e.queue.submit([a.finish()])}async function Cc(e,t,n,r,i,a){let o=e.createCommandEncoder(),s=o.beginComputePass();return s.setPipeline(await t),s.setBindGroup(0,n),s.setBindGroup(1,r),s.dispatchWorkgroups(Math.ceil(i/8),Math.ceil(a/8)),s.end(),o}async function wc(e,t,n,r,i,a){t.copyBufferToBuffer(n,r,i,0,a),e.queue.submit([t.finish()]),await i.mapAsync(GPUMapMode.READ);let o=i.getMappedRange().slice(0);return i.unmap(),o}var Tc=32767,Ec=0x3fffffff,Dc=e=>e>>>30,Oc=mc.RECORD_WORDS;function kc(e,t){let n=e=>Math.ceil(e/mc.TYPE_ALIGN)*mc.TYPE_ALIGN,r=e.map(e=>n(e.size[0]*e.size[1]*e.size[2])),i=new Uint32Array(r.reduce((e,t)=>e+t,0)),a=new Uint32Array(e.length*Oc),o=0;return e.forEach((e,n)=>{i.fill((mc.SOLID|e.material)>>>0,o,o+e.size[0]*e.size[1]*e.size[2]);let[s,c,l]=e.min.map(e=>e*128),[u,d,f]=e.size,p=n*Oc;a[p]=s&2097151|(c&2047)<<21,a[p+1]=l&2097151|(c>>>11&255)<<21|(f>>>4&7)<<29,a[p+2]=mc.IDENTITY_ROTATION[0],a[p+3]=mc.IDENTITY_ROTATION[1]&4095|(t+o)/mc.TYPE_ALIGN<<12,a[p+4]=mc.LOCAL_ID|u<<14|d<<21|(f&15)<<28,o+=r[n]}),{types:i,records:a}}function Ac(e,t){let n=[e&16383,e>>>14&16383,e>>>28|(t&1023)<<4].map(e=>(e-8192)/8192),r=n[0]*n[0]+n[1]*n[1]+n[2]*n[2],i=Math.sqrt(Math.max(1-r,0));return n.splice(t>>>10&3,0,i),n}function jc(e,t){let n=t*Oc,r=e[n+4];if(!r)return;let[i,a,o,s]=[e[n],e[n+1],e[n+2],e[n+3]],c=[r>>>14&127,r>>>21&127,r>>>28&15|(a>>>29&7)<<4],l=[i&2097151,i>>>21|(a>>>21&255)<<11,a&2097151].map(e=>e/128),u=Ac(o,s&4095),[d,f,p,m]=[-u[0],-u[1],-u[2],u[3]],h=[1/0,1/0,1/0],g=[-1/0,-1/0,-1/0];for(let e=0;e<8;e++){let t=e&1?c[0]:0,n=e&2?c[1]:0,r=e&4?c[2]:0,i=2*(f*r-p*n),a=2*(p*t-d*r),o=2*(d*n-f*t),s=[t+m*i+(f*o-p*a),n+m*a+(p*i-d*o),r+m*o+(d*a-f*i)];for(let e=0;e<3;e++)h[e]=Math.min(h[e],s[e]+l[e]),g[e]=Math.max(g[e],s[e]+l[e])}return[h.map(e=>e-q.BOUNDS_PAD),g.map(e=>e+q.BOUNDS_PAD)]}var Mc=new Float32Array(1),Nc=new Int32Array(Mc.buffer);function Pc(e,t){let n=t?e+q.F32_PAD:e-q.F32_PAD;Mc[0]=n;let r=Mc[0];return(t?r>=n:r<=n)?r:r===0?(Nc[0]=1,t?Mc[0]:-Mc[0]):(Nc[0]+=r>0===t?1:-1,Mc[0])}function Fc(e,t){e.fill(1/0,6*t,6*t+3),e.fill(-1/0,6*t+3,6*t+6)}function Ic(e,t,n,r){for(let i=0;i<3;i++)e[6*t+i]=Math.min(e[6*t+i],n[6*r+i]),e[6*t+3+i]=Math.max(e[6*t+3+i],n[6*r+3+i])}function Lc(e,t){let n=Math.max(e[6*t+3]-e[6*t],0),r=Math.max(e[6*t+4]-e[6*t+1],0),i=Math.max(e[6*t+5]-e[6*t+2],0);return n*r+r*i+i*n}function Rc(e,t,n){return n<=t?0:Math.min(Math.floor((e-t)/(n-t)*q.BINS),q.BINS-1)}function zc(e){let t=e.length/6,n=new Float64Array(6*t);for(let r=0;r<t;r++)for(let t=0;t<3;t++)n[6*r+t]=n[6*r+3+t]=.5*(e[6*r+t]+e[6*r+3+t]);let r=Int32Array.from({length:t},(e,t)=>t),i=q.BINS,a=new Float64Array(18*i),o=new Int32Array(3*i),s=new Float64Array(6),c=new Float64Array(i),l=new Int32Array(i),u=(e,t,n,i)=>{Fc(e,0);for(let a=n;a<i;a++)Ic(e,0,t,r[a])},d=new Float64Array(6),f=(t,f)=>{u(d,n,t,f);let p=d.slice(0,3),m=d.slice(3,6);for(let e=0;e<3*i;e++)Fc(a,e);o.fill(0);for(let s=t;s<f;s++){let t=r[s];for(let r=0;r<3;r++){let s=r*i+Rc(n[6*t+r],p[r],m[r]);Ic(a,s,e,t),o[s]+=1}}let h;for(let e=0;e<3;e++){if(m[e]<=p[e])continue;Fc(s,0);let t=0;for(let n=i-1;n>=1;n--)Ic(s,0,a,e*i+n),t+=o[e*i+n],c[n]=Lc(s,0),l[n]=t;Fc(s,0),t=0;for(let n=1;n<i;n++){if(Ic(s,0,a,e*i+n-1),t+=o[e*i+n-1],t===0||l[n]===0)continue;let r=Lc(s,0)*t+c[n]*l[n];(!h||r<h.cost)&&(h={axis:e,lo:p[e],hi:m[e],bin:n,cost:r})}}return h},p=(e,t)=>{u(d,n,e,t);let i=0;for(let e=1;e<3;e++)d[3+e]-d[e]>=d[3+i]-d[i]&&(i=e);return r.subarray(e,t).sort((e,t)=>n[6*e+i]-n[6*t+i]||e-t),e+(t-e>>1)},m=(t,i,a)=>{let o=new Float64Array(6);if(u(o,e,t,i),i-t===1)return{box:o,prim:r[t]};let s=a<q.SAH_DEPTH&&i-t>4?f(t,i):void 0,c;if(s){let e=e=>Rc(n[6*e+s.axis],s.lo,s.hi)<s.bin,[a,o]=[t,i];for(;a<o;)e(r[a])?a+=1:(--o,[r[a],r[o]]=[r[o],r[a]]);c=a}else c=p(t,i);return{box:o,kids:[m(t,c,a+1),m(c,i,a+1)],prim:0}};return m(0,t,0)}function Bc(e){let t=[],n=[];for(let r=0;r<e.length/Oc;r++){let i=jc(e,r);i&&(n.push(i),t.push(r))}let r=new Float64Array(6*n.length);return n.forEach(([e,t],n)=>{r.set(e,6*n),r.set(t,6*n+3)}),{slots:t,boxes:r}}function Vc(e,t){if(Fc(e.box,0),!e.kids)Ic(e.box,0,t,e.prim);else for(let n of e.kids)Vc(n,t),Ic(e.box,0,n.box,0)}var Hc=24;function Uc(e,t){let n=[],r=e=>{let i=n.length,a=new Uint32Array(q.NODE_WORDS),o=new Float32Array(a.buffer,0,Hc);return o.fill(q.FAR),a.fill(q.NONE,Hc),n.push(a),(e.kids?e.kids.flatMap(e=>e.kids?e.kids:[e]):[e]).forEach((e,n)=>{for(let t=0;t<3;t++)o[8*t+n]=Pc(e.box[t],!1),o[8*t+4+n]=Pc(e.box[3+t],!0);a[Hc+n]=e.kids?r(e):(q.LEAF|t[e.prim])>>>0}),i};r(e);let i=new Uint32Array(n.length*q.NODE_WORDS);return n.forEach((e,t)=>i.set(e,t*q.NODE_WORDS)),i}function Wc(e){let t=new Float32Array(e.buffer,e.byteOffset,e.length),n=new Float64Array(6),r=new Float64Array(6);Fc(r,0);let i=0;for(let a=0;a<e.length/q.NODE_WORDS;a++){let o=a*q.NODE_WORDS;for(let s=0;s<4;s++){let c=e[o+Hc+s];if(c!==q.NONE){for(let e=0;e<3;e++)n[e]=t[o+8*e+s],n[3+e]=t[o+8*e+4+s];a===0&&Ic(r,0,n,0),c&q.LEAF||(i+=Lc(n,0))}}}return 1+i/Lc(r,0)}function Gc(e){return new Kc().update(e)}var Kc=class{slots=[];tree;builtVisits=0;update(e){let{slots:t,boxes:n}=Bc(e);if(t.length===0)return this.tree=void 0,this.slots=[],new Uint32Array;let r=t.length===this.slots.length&&t.every((e,t)=>e===this.slots[t]);if(this.tree&&r){Vc(this.tree,n);let e=Uc(this.tree,t);if(Wc(e)<=q.REFIT_SLACK*this.builtVisits)return e}this.tree=zc(n),this.slots=t;let i=Uc(this.tree,t);return this.builtVisits=Wc(i),i}};function qc(e){return{chunks:e.words(0),blocks:e.words(2),voxels:e.words(3)}}var Jc=class{h1=0xdeadbeef;h2=0x41c6ce57;word(e){this.h1=Math.imul(this.h1^e,0x9e3779b1),this.h2=Math.imul(this.h2^e,0x5f356495)}words(e){for(let t=0;t<e.length;t++)this.word(e[t])}digest(){let e=Math.imul(this.h1^this.h1>>>16,0x85ebca6b);e^=Math.imul(this.h2^this.h2>>>13,0xc2b2ae35);let t=Math.imul(this.h2^this.h2>>>16,0x85ebca6b);return t^=Math.imul(e^e>>>13,0xc2b2ae35),4294967296*(2097151&t)+(e>>>0)}},Yc=e=>Dc(e)===1?e&Tc:0;function Xc(e,t){let n=new Jc,r=e.chunks[t];if(Dc(r)===2){let t=r&Ec;for(let r=t;r<t+64;r++){let t=e.blocks[r];if(Dc(t)===2){let r=t&Ec;n.word(1),n.words(e.voxels.subarray(r,r+32))}else n.word(0),n.word(Yc(t))}}else n.word(2),n.word(Yc(r));return n.digest()}function Zc(e,t){let n=e.filter(e=>e.id===t).map(e=>[e.lo>>2,e.hi+3>>2]).sort((e,t)=>e[0]-t[0]),r=[];for(let e of n){let t=r[r.length-1];t&&e[0]<=t[1]?t[1]=Math.max(t[1],e[1]):r.push(e)}return r}function Qc(e,t,n){if(n===0||e.length===0)return!1;let r=0,i=e.length;for(;r<i;){let n=r+i>>1;e[n][1]<=t?r=n+1:i=n}return r<e.length&&e[r][0]<t+n}function $c(e,t){let n=[0,1,2].map(t=>Math.max(0,Math.floor(e[0][t]/16))),r=[0,1,2].map(n=>Math.min(t[n]-1,Math.floor(e[1][n]/16))),i=[];for(let e=n[2];e<=r[2];e++)for(let a=n[1];a<=r[1];a++)for(let o=n[0];o<=r[0];o++)i.push(o+t[0]*(a+t[1]*e));return i}var el=class e{prints;records;constructor(e){let t=qc(e);this.prints=new Float64Array(t.chunks.length);for(let e=0;e<t.chunks.length;e++)this.prints[e]=Xc(t,e);this.records=e.words(7).slice()}update(t,n){let r=qc(t),i=e=>Zc(n,e);if(r.chunks.length!==this.prints.length||n.some(e=>e.id===4||e.id===6)){let n=new e(t);return this.prints=n.prints,this.records=n.records,`everything`}let[a,o,s,c]=[0,2,3,7].map(i),l=e=>{if(Qc(a,e,1))return!0;let t=r.chunks[e];if(Dc(t)!==2)return!1;let n=t&Ec;if(Qc(o,n,64))return!0;if(s.length===0)return!1;for(let e=n;e<n+64;e++){let t=r.blocks[e];if(Dc(t)===2&&Qc(s,t&0x3fffffff,32))return!0}return!1},u=new Set;if(a.length+o.length+s.length>0)for(let e=0;e<r.chunks.length;e++){if(!l(e))continue;let t=Xc(r,e);t!==this.prints[e]&&(this.prints[e]=t,u.add(e))}if(c.length>0){let[e,n]=[this.records,t.words(7)],r=t.size.map(e=>Math.ceil(e/16)),i=Math.max(e.length,n.length)/Oc;for(let t=0;t<i;t++){let i=t*Oc,a=!0;for(let t=i;t<i+Oc;t++)a&&=(e[t]??0)===(n[t]??0);if(!a)for(let i of[e,n]){let e=t<i.length/Oc?jc(i,t):void 0;if(e)for(let t of $c(e,r))u.add(t)}}this.records=n.slice()}return[...u].sort((e,t)=>e-t)}},tl=`// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the
// Rust code, the world's storage bindings.
struct WorldInfo {
    // World size in voxels.
    size: vec3<u32>,
    // Slots of the instance buffer on the device, the world's and then the local
    // instances' (records of 5 words; 0: no instance to trace).
    instance_slots: u32,
    // World size in chunks.
    chunks: vec3<u32>,
    // Cells a ray may visit before it counts as a miss.
    max_steps: u32,
}
@group(0) @binding(0) var<uniform> world_info: WorldInfo;
struct FrameInfo {
    // Camera position, integer part (floor).
    cam_int: vec3<i32>,
    // Image width in pixels.
    width: u32,
    // Camera position, fractional part in [0, 1).
    cam_frac: vec3<f32>,
    // Image height in pixels.
    height: u32,
    // View direction.
    forward: vec3<f32>,
    // The run's seed.
    seed: u32,
    // Image right, scaled by a·W/H.
    right: vec3<f32>,
    // Number of the sample this dispatch adds.
    sample: u32,
    // Image up, scaled by a.
    up: vec3<f32>,
    // 1 when a temporal pass has a history to blend with (0 for the path tracer).
    history: u32,
}
struct LightInfo {
    // Uniform sky: its radiance. Physical sky: the irradiance of the sun lighting it.
    sky: vec3<f32>,
    // 1 for the physical sky.
    sky_physical: u32,
    // Unit vector toward the sun (the sun lighting the physical sky when it is off).
    sun_dir: vec3<f32>,
    // 1 when the sun shines (its disc and its samples).
    sun_on: u32,
    // The disc's radiance.
    sun_disc: f32,
    // The weight of one disc sample: radiance times solid angle.
    sun_weight: f32,
    // 1 − cos of the disc's angular radius.
    sun_omc: f32,
    // Scattered rays after the camera ray.
    bounces: u32,
}
struct GiInfo {
    // Frames rendered in this history before this one.
    frame: u32,
    // The long-term TAA slot this frame writes (\`frame % TAA_SLOTS\`).
    taa_slot: u32,
    // Earlier frames the TAA may read (at most \`TAA_SLOTS − 1\`).
    taa_valid: u32,
    // The first frame rendered after the newest change of the materials, or of more
    // chunks than are marked one by one (0: none): the near-change rule everywhere.
    edit_frame: u32,
    // The first frame rendered after the newest change of any chunk, entity moves
    // included (0: none): the still path keeps no sample from before it.
    change_frame: u32,
    // This frame's jitter in the pixel, x (a point of a 32-point (0, 5, 2)-net).
    jitter_x: f32,
    // This frame's jitter in the pixel, y.
    jitter_y: f32,
    // 8×8 regions across.
    regions_x: u32,
    // 8×8 regions down.
    regions_y: u32,
    // Samples the sample ring holds.
    ring_capacity: u32,
    // 1 when the bilateral denoiser runs.
    denoise: u32,
    // Where each pixel's own secondary sample starts in \`mem\` (tagged with the
    // frame that traced it).
    off_own: u32,
    // Where the atmosphere table starts in \`mem\` (vec4 words; the cameras start at 0).
    off_lut: u32,
    // Where the first-hit surfaces start in \`mem\`.
    off_gbuf: u32,
    // Where the first-hit materials start in \`mem\`.
    off_gmat: u32,
    // Where the first-hit light starts in \`mem\`.
    off_emitted: u32,
    // Where the TAA's per-pixel sums and ranges start in \`mem\`.
    off_taa_info: u32,
    // Where the incoming light starts in \`mem\`.
    off_illum: u32,
    // Where the denoiser's intermediate starts in \`mem\`.
    off_illum2: u32,
    // Where the results start in \`mem\`.
    off_result: u32,
    // Where the refined samples start in \`mem\`.
    off_refined: u32,
    // Where the regions' statistics start in \`mem\`.
    off_region_info: u32,
    // Where the sample ring starts in \`mem\`.
    off_ring: u32,
    // Where the queued pixels start in \`words\`.
    off_queue_list: u32,
}
const STATE_SHIFT: u32 = 30u;
const STATE_EMPTY: u32 = 0u;
const STATE_FULL: u32 = 1u;
const STATE_MIXED: u32 = 2u;
const PAYLOAD: u32 = 1073741823u;
const MAX_MATERIAL: u32 = 32767u;
const VOXEL_SOLID: u32 = 32768u;
const CHUNK_FIELD_BITS: u32 = 5u;
const CELL_FIELD_BITS: u32 = 2u;
const KIND_DIFFUSE: u32 = 0u;
const KIND_EMISSIVE: u32 = 1u;
const KIND_METAL: u32 = 2u;
const KIND_MIRROR: u32 = 3u;
const ENTITY_SOLID: u32 = 2147483648u;
const TYPE_ALIGN: u32 = 64u;
const RECORD_WORDS: u32 = 5u;
const NO_ENTITY: u32 = 16383u;
const NODE_WORDS: u32 = 28u;
const BVH_STACK: u32 = 64u;
const BVH_LEAF: u32 = 2147483648u;
const BVH_NONE: u32 = 4294967295u;
const BVH_FAR: f32 = 1e30f;
const SURFACE_OFFSET: f32 = 0.01f;
const MIN_ALPHA: f32 = 0.001f;
const PI: f32 = 3.1415927f;
const PLANET_RADIUS: f32 = 6360000.0f;
const ATMOSPHERE_HEIGHT: f32 = 60000.0f;
const EYE_HEIGHT: f32 = 100.0f;
const VIEW_STEPS: u32 = 24u;
const LIGHT_STEPS: u32 = 6u;
const RAYLEIGH: vec3<f32> = vec3<f32>(5.802e-6f, 1.3558e-5f, 3.31e-5f);
const RAYLEIGH_SCALE: f32 = 8000.0f;
const MIE_SCATTER: f32 = 3.996e-6f;
const MIE_EXTINCTION: f32 = 4.44e-6f;
const MIE_SCALE: f32 = 1200.0f;
const MIE_G: f32 = 0.8f;
const OZONE: vec3<f32> = vec3<f32>(6.5e-7f, 1.881e-6f, 8.5e-8f);
const OZONE_CENTRE: f32 = 25000.0f;
const OZONE_HALF_WIDTH: f32 = 15000.0f;
// The first word of each buffer in \`world\`.
struct WorldOffsets {
    chunks: u32,
    blocks: u32,
    voxels: u32,
    materials: u32,
    entity_types: u32,
    entity_instances: u32,
    entity_hierarchy: u32,
    structure: u32,
}
@group(0) @binding(1) var<uniform> world_offsets: WorldOffsets;
@group(0) @binding(2) var<storage, read> world: array<u32>;
fn chunk_word(i: u32) -> u32 { return world[world_offsets.chunks + i]; }
fn block_word(i: u32) -> u32 { return world[world_offsets.blocks + i]; }
fn voxel_word(i: u32) -> u32 { return world[world_offsets.voxels + i]; }
fn material_word(i: u32) -> u32 { return world[world_offsets.materials + i]; }
fn entity_type_word(i: u32) -> u32 { return world[world_offsets.entity_types + i]; }
fn instance_word(i: u32) -> u32 { return world[world_offsets.entity_instances + i]; }
fn hierarchy_word(i: u32) -> u32 { return world[world_offsets.entity_hierarchy + i]; }
fn structure_word(i: u32) -> u32 { return world[world_offsets.structure + i]; }

// The world buffers (docs/FORMAT.md §5) and how to read their cells.
//
// Generated by naadf-client (client/src/gpu/shaders.rs) from the Rust definitions, in the
// prelude before this file:
// - the parameters \`world_info: WorldInfo\` (size in voxels and chunks, the instance
//   buffer's slots, the step budget);
// - the constants of the cell layout (STATE_*, PAYLOAD, MAX_MATERIAL, VOXEL_SOLID,
//   CHUNK_FIELD_BITS, CELL_FIELD_BITS), the material kinds (KIND_*), the entity layout
//   (ENTITY_SOLID, TYPE_ALIGN, RECORD_WORDS, NO_ENTITY), the instance hierarchy's (NODE_WORDS,
//   BVH_*) and the frame modes (MODE_*);
// - the storage bindings and the accessors \`chunk_word\`, \`block_word\`, \`voxel_word\`,
//   \`material_word\`, \`entity_type_word\`, \`instance_word\`, \`hierarchy_word\` (and
//   \`structure_word\` for the comparison traversals): a buffer larger than the adapter's
//   storage-binding limit is split across several bindings, and the accessor picks the
//   part.

// State of a chunk or block cell: STATE_EMPTY, STATE_FULL or (also for state 3)
// STATE_MIXED.
fn cell_state(c: u32) -> u32 {
    return min(c >> STATE_SHIFT, STATE_MIXED);
}

// Field \`dir\` (order −x, +x, −y, +y, −z, +z) of a packed AADF.
fn aadf_field(word: u32, dir: u32, bits: u32) -> u32 {
    return (word >> (bits * dir)) & ((1u << bits) - 1u);
}

// The index of chunk \`c\` in a world of \`chunks\` chunks (\`world_info.chunks\`). Loops read
// \`world_info\` once before they start and pass its fields: it is a storage buffer, and a
// storage read in every step is a bounds-checked load on lavapipe.
fn chunk_index(c: vec3<u32>, chunks: vec3<u32>) -> u32 {
    return c.x + chunks.x * (c.y + chunks.y * c.z);
}

fn index4(p: vec3<u32>) -> u32 {
    return p.x + 4u * p.y + 16u * p.z;
}

// Voxel \`i\` (0..64) of the voxel group starting at word \`ptr\`.
fn group_voxel(ptr: u32, i: u32) -> u32 {
    return (voxel_word(ptr + i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

// A material's entry (docs/FORMAT.md §5.4).
struct Material {
    kind: u32,
    albedo: vec3<f32>,
    emission: f32,
    roughness: f32,
}

fn material(id: u32) -> Material {
    let w0 = material_word(4u * id);
    let w1 = material_word(4u * id + 1u);
    let w2 = material_word(4u * id + 2u);
    let rg = unpack2x16float(w1);
    let be = unpack2x16float(w2);
    return Material(w0 & 3u, vec3<f32>(rg.x, rg.y, be.x), be.y, unpack2x16float(w0).y);
}

// Rays and the event model every traversal shares (world/src/traverse/ray.rs, in f32).
//
// A ray keeps its origin split into an integer part \`o_int\` and a fraction \`o_frac\` in [0, 1)
// (docs/NAADF.md §9), so precision does not depend on where in the world it starts.
// The direction \`d\` is kept exactly as given (not renormalised, which would move the line
// by an f32 rounding): times are in units of |d| and the ray's \`len\` converts them to
// distances. Every decision compares plane-crossing times from the one function \`t_at\`,
// so the traversal is a consistent walk of the event order "(t, axis), x before y before
// z at equal t"; it departs from the CPU's f64 order only where two crossings are within
// f32 rounding of each other.

// A cell bound beyond any world for unconstrained axes (the CPU walk uses 2^40, which no
// i32 holds).
const FAR_CELL: i32 = 1073741824;
const T_INF: f32 = 3.0e38;
const NO_AXIS: u32 = 3u;

struct Ray {
    o_int: vec3<i32>,
    o_frac: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    len: f32,
}

fn ray_new(o_int: vec3<i32>, o_frac: vec3<f32>, d: vec3<f32>) -> Ray {
    // The inverse of a zero component is never read: such axes never cross a plane.
    let safe = select(vec3<f32>(1.0), d, d != vec3<f32>(0.0));
    return Ray(o_int, o_frac, d, 1.0 / safe, length(d));
}

// A ray from an unsplit origin.
fn ray_from(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(o);
    return ray_new(vec3<i32>(fl), min(o - fl, vec3<f32>(0.99999994)), d);
}

// The ray's point at time \`t\`, relative to its integer origin.
fn ray_local(r: Ray, t: f32) -> vec3<f32> {
    return r.o_frac + r.d * t;
}

// A ray starting at \`p\` (relative to \`r\`'s integer origin) along \`d\`.
fn ray_at(r: Ray, p: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(p);
    return ray_new(r.o_int + vec3<i32>(fl), min(p - fl, vec3<f32>(0.99999994)), d);
}

// Time at which the ray crosses plane \`k\` of \`axis\`.
fn t_at(r: Ray, a: u32, k: i32) -> f32 {
    return (f32(k - r.o_int[a]) - r.o_frac[a]) * r.inv[a];
}

// Whether the crossing of plane \`k\` of axis \`b\` comes before the event \`(t, a)\`.
fn crossed(r: Ray, b: u32, k: i32, t: f32, a: u32) -> bool {
    let tb = t_at(r, b, k);
    return tb < t || (tb == t && b < a);
}

// The cell of axis \`b\` right after event \`(t, a)\`, known to lie in \`lo..=hi\`.
fn cell_after(r: Ray, b: u32, t: f32, a: u32, lo: i32, hi: i32) -> i32 {
    let d = r.d[b];
    if lo == hi || d == 0.0 {
        return lo;
    }
    let p = r.o_frac[b] + d * t;
    let fl = floor(p);
    var k = clamp(i32(fl) + r.o_int[b], lo, hi);
    let f = p - fl;
    // Far from a plane the floor is certain; near one, decide by crossing times.
    let tol = 4e-6 * (abs(d * t) + 1.0);
    if f > tol && f < 1.0 - tol {
        return k;
    }
    if d > 0.0 {
        while k < hi && crossed(r, b, k + 1, t, a) {
            k += 1;
        }
        while k > lo && !crossed(r, b, k, t, a) {
            k -= 1;
        }
    } else {
        while k > lo && crossed(r, b, k, t, a) {
            k -= 1;
        }
        while k < hi && !crossed(r, b, k + 1, t, a) {
            k += 1;
        }
    }
    return k;
}

// Where a ray begins inside the box [0, size): its first cell, the time it is entered and
// the axis whose plane it crossed (NO_AXIS when the origin is inside). \`ok\` is false when
// the ray misses the box.
struct Entry {
    cell: vec3<i32>,
    t: f32,
    axis: u32,
    ok: bool,
}

fn ray_entry(r: Ray, size: vec3<i32>) -> Entry {
    let start = r.o_int;
    var miss = Entry(vec3<i32>(0), 0.0, NO_AXIS, false);
    if all(start >= vec3<i32>(0)) && all(start < size) {
        return Entry(start, 0.0, NO_AXIS, true);
    }
    // The last slab-entry event, in (t, axis) order.
    var bt = 0.0;
    var ba = NO_AXIS;
    for (var a = 0u; a < 3u; a++) {
        var plane: i32;
        if start[a] < 0 {
            if r.d[a] <= 0.0 {
                return miss;
            }
            plane = 0;
        } else if start[a] >= size[a] {
            if r.d[a] >= 0.0 {
                return miss;
            }
            plane = size[a];
        } else {
            continue;
        }
        let t = t_at(r, a, plane);
        if ba == NO_AXIS || t >= bt {
            bt = t;
            ba = a;
        }
    }
    var cell = vec3<i32>(0);
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            cell[b] = select(size[b] - 1, 0, r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            cell[b] = cell_after(r, b, bt, ba, start[b], FAR_CELL);
        } else if r.d[b] < 0.0 {
            cell[b] = cell_after(r, b, bt, ba, -FAR_CELL, start[b]);
        } else {
            cell[b] = start[b];
        }
    }
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return miss;
    }
    return Entry(cell, bt, ba, true);
}

// When a ray inside the box [0, size] leaves it: the first crossing of a far plane it moves
// toward (world/src/traverse/ray.rs \`leave_time\`).
fn leave_time(r: Ray, size: vec3<i32>) -> f32 {
    var t = T_INF;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            t = min(t, t_at(r, a, select(0, size[a], r.d[a] > 0.0)));
        }
    }
    return t;
}

// Leaving the empty cuboid made of \`cell\` extended by \`skip\` cells toward the ray on each
// axis: the exit event and the cell entered by it.
struct Exit {
    t: f32,
    axis: u32,
    next: vec3<i32>,
}

fn ray_exit(r: Ray, cell: vec3<i32>, skip: vec3<i32>) -> Exit {
    var bound = vec3<i32>(0);
    var bt = T_INF;
    var ba = 0u;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] == 0.0 {
            continue;
        }
        bound[a] = select(cell[a] - skip[a], cell[a] + 1 + skip[a], r.d[a] > 0.0);
        let t = t_at(r, a, bound[a]);
        if t < bt {
            bt = t;
            ba = a;
        }
    }
    var next = cell;
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            next[b] = select(bound[b] - 1, bound[b], r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b], cell[b] + skip[b]);
        } else if r.d[b] < 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b] - skip[b], cell[b]);
        }
    }
    return Exit(bt, ba, next);
}

// Amanatides–Woo state in the same event order (ties step the lowest axis first).
struct Dda {
    cell: vec3<i32>,
    tmax: vec3<f32>,
    t: f32,
    axis: u32,
}

fn dda_start(r: Ray, e: Entry) -> Dda {
    var tmax = vec3<f32>(T_INF);
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            tmax[a] = t_at(r, a, select(e.cell[a], e.cell[a] + 1, r.d[a] > 0.0));
        }
    }
    return Dda(e.cell, tmax, e.t, e.axis);
}

fn dda_advance(r: Ray, s: ptr<function, Dda>) {
    var a = 0u;
    if (*s).tmax[1] < (*s).tmax[a] {
        a = 1u;
    }
    if (*s).tmax[2] < (*s).tmax[a] {
        a = 2u;
    }
    (*s).t = (*s).tmax[a];
    let c = (*s).cell[a] + select(-1, 1, r.d[a] > 0.0);
    (*s).cell[a] = c;
    (*s).axis = a;
    (*s).tmax[a] = t_at(r, a, select(c, c + 1, r.d[a] > 0.0));
}

// The first solid voxel along a ray (of the world, or of an entity: then voxel and normal
// are entity-local).
struct Hit {
    hit: bool,
    // The step budget ran out (counts as a miss).
    exhausted: bool,
    voxel: vec3<i32>,
    // Axis of the entry face (NO_AXIS: the origin was inside the voxel).
    axis: u32,
    // Entry-face normal (zero when the origin was inside).
    normal: vec3<i32>,
    // Time of entry, in units of the ray's |d|.
    t: f32,
    material: u32,
    steps: u32,
    // Entity id, or NO_ENTITY (generated in the prelude).
    entity: u32,
}

fn no_hit(steps: u32) -> Hit {
    return Hit(false, false, vec3<i32>(0), NO_AXIS, vec3<i32>(0), T_INF, 0u, steps, NO_ENTITY);
}

fn make_hit(r: Ray, cell: vec3<i32>, t: f32, axis: u32, material: u32, steps: u32) -> Hit {
    var n = vec3<i32>(0);
    if axis != NO_AXIS {
        n[axis] = select(1, -1, r.d[axis] > 0.0);
    }
    return Hit(true, false, cell, axis, n, t, material, steps, NO_ENTITY);
}

// One full trace: the world loop (traverse.wgsl or grid.wgsl) through the static world,
// then the instances whose world boxes the ray crosses before the world's hit or exit,
// found through their hierarchy (docs/NAADF.md §11): the GPU twin of
// world/src/traverse/entities.rs. Only the nearest entity hit (lowest id at equal times)
// survives, and only if it comes strictly before the world's hit or exit. Local instances
// (previews, markers: world/src/entity/local.rs) follow the world's records and carry the id
// NO_ENTITY, so their hits read as static geometry to everything that follows entity ids.

// How the world loop ended.
const END_HIT: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_EXHAUSTED: u32 = 3u;

struct WorldTrace {
    hit: Hit,
    end: u32,
    // When the ray entered the world, and when it hit or left it.
    t_entry: f32,
    t_end: f32,
}

// The end of a world loop whose step budget ran out at time \`t\` (entered at \`t_entry\`).
fn ran_out(t_entry: f32, t: f32) -> WorldTrace {
    var h = no_hit(world_info.max_steps);
    h.exhausted = true;
    return WorldTrace(h, END_EXHAUSTED, t_entry, t);
}

var<private> best_entity: Hit;
// The inverse rotation of \`best_entity\`'s instance.
var<private> best_rotation: vec4<f32>;
// Entity-grid cells visited (added to the step count of an entity hit).
var<private> entity_steps: u32;
// Whether the last \`trace\` returned an instance's hit (a local instance's has no entity id).
var<private> hit_instance: bool;

// Whether the world holds any instance. The host builds a pipeline for each value and
// picks the one that matches its world: a device that runs neighbouring rays in lock step
// may run code that no ray takes, and without instances none of the walk is compiled.
override HAS_INSTANCES: bool = true;

// How many instances the walk finds before it stops to test them.
const INSTANCE_BATCH: u32 = 8u;

// The walk's node stack and found instances, at module scope, so that an invocation holds
// (and zeroes) one of each rather than one for every trace inlined into it.
var<private> bvh_stack: array<u32, BVH_STACK>;
var<private> found_t: array<f32, INSTANCE_BATCH>;
var<private> found_slot: array<u32, INSTANCE_BATCH>;

// Walks the instance hierarchy (world/src/entity/bvh.rs: four-wide nodes of NODE_WORDS
// words, the children's f32 boxes axis by axis, then their references) and tests every
// instance whose box the ray is inside at some t in [t_lo, t_hi] (or up to the best entity
// hit so far). Boxes are padded and rounded outward, so the f32 test never rejects an
// instance the ray can hit. The walk gathers up to INSTANCE_BATCH instances, then tests them
// in the order the ray enters their boxes, stopping at a box that starts after the best hit,
// and goes on while nodes are left. Testing outside the walk's loop keeps that loop small,
// which is what costs on a device that runs neighbouring rays in lock step. With \`any_hit\`
// it returns at the first hit before \`t_hi\`.
fn find_instances(r: Ray, t_lo: f32, t_hi: f32, any_hit: bool) {
    // The world loop says whether its structure is traced with entities: the comparison
    // trees hold geometry only.
    if !TRACES_ENTITIES || !HAS_INSTANCES || world_info.instance_slots == 0u {
        return;
    }
    // 1/d, with ±FAR for axes the ray does not move along.
    let inv = select(1.0 / r.d, select(vec3<f32>(BVH_FAR), vec3<f32>(-BVH_FAR), r.d < vec3<f32>(0.0)), r.d == vec3<f32>(0.0));
    let o = vec3<f32>(r.o_int);
    bvh_stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        var far_limit = t_hi * 1.000001 + 1e-3;
        if best_entity.hit {
            far_limit = min(far_limit, best_entity.t * 1.000001 + 1e-3);
        }
        // A node adds at most four instances, so one is taken while four places are left.
        var found = 0u;
        while sp > 0u && found + 4u <= INSTANCE_BATCH {
            sp -= 1u;
            let base = bvh_stack[sp] * NODE_WORDS;
            // The four lanes at once, axis by axis.
            let tx0 = ((node_lanes(base) - o.x) - r.o_frac.x) * inv.x;
            let tx1 = ((node_lanes(base + 4u) - o.x) - r.o_frac.x) * inv.x;
            let ty0 = ((node_lanes(base + 8u) - o.y) - r.o_frac.y) * inv.y;
            let ty1 = ((node_lanes(base + 12u) - o.y) - r.o_frac.y) * inv.y;
            let tz0 = ((node_lanes(base + 16u) - o.z) - r.o_frac.z) * inv.z;
            let tz1 = ((node_lanes(base + 20u) - o.z) - r.o_frac.z) * inv.z;
            let near = max(vec4<f32>(t_lo - 1e-3), max(min(tx0, tx1), max(min(ty0, ty1), min(tz0, tz1))));
            let far = min(vec4<f32>(far_limit), min(max(tx0, tx1), min(max(ty0, ty1), max(tz0, tz1))));
            let child = vec4<u32>(hierarchy_word(base + 24u), hierarchy_word(base + 25u), hierarchy_word(base + 26u), hierarchy_word(base + 27u));
            let entered = !(near > far) & (child != vec4<u32>(BVH_NONE));
            // Each lane in turn: no loop, so that no lane's index is dynamic.
            if entered.x {
                keep_lane(child.x, near.x, &sp, &found);
            }
            if entered.y {
                keep_lane(child.y, near.y, &sp, &found);
            }
            if entered.z {
                keep_lane(child.z, near.z, &sp, &found);
            }
            if entered.w {
                keep_lane(child.w, near.w, &sp, &found);
            }
        }
        // Nearest box first, until one starts after the best hit (whose own box started no
        // later: the boxes are padded beyond the f32 test's rounding).
        for (var left = found; left > 0u; left--) {
            var k = 0u;
            for (var j = 1u; j < left; j++) {
                if found_t[j] < found_t[k] {
                    k = j;
                }
            }
            if best_entity.hit && found_t[k] > best_entity.t {
                break;
            }
            test_instance(r, found_slot[k] * RECORD_WORDS, t_lo);
            if any_hit && best_entity.hit && best_entity.t < t_hi {
                return;
            }
            found_t[k] = found_t[left - 1u];
            found_slot[k] = found_slot[left - 1u];
        }
    }
}

// Keeps a lane the ray enters at \`near\`: an instance among the found ones, or a node on the
// stack.
fn keep_lane(c: u32, near: f32, sp: ptr<function, u32>, found: ptr<function, u32>) {
    if (c & BVH_LEAF) != 0u {
        found_t[*found] = near;
        found_slot[*found] = c & ~BVH_LEAF;
        *found += 1u;
    } else if *sp < BVH_STACK {
        bvh_stack[*sp] = c;
        *sp += 1u;
    }
}

// Four lanes' planes of one axis, from word \`at\` of the hierarchy.
fn node_lanes(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4<u32>(hierarchy_word(at), hierarchy_word(at + 1u), hierarchy_word(at + 2u), hierarchy_word(at + 3u)));
}

// Decodes a smallest-three quaternion (world/src/entity/pack.rs).
fn decode_quat(w0: u32, w1: u32) -> vec4<f32> {
    let s = vec3<f32>(vec3<u32>(w0 & 0x3FFFu, (w0 >> 14u) & 0x3FFFu, (w0 >> 28u) | ((w1 & 0x3FFu) << 4u)));
    let small = (s - 8192.0) / 8192.0;
    let rest = sqrt(max(1.0 - dot(small, small), 0.0));
    let k = (w1 >> 10u) & 3u;
    if k == 0u {
        return vec4<f32>(rest, small.x, small.y, small.z);
    } else if k == 1u {
        return vec4<f32>(small.x, rest, small.y, small.z);
    } else if k == 2u {
        return vec4<f32>(small.x, small.y, rest, small.z);
    }
    return vec4<f32>(small, rest);
}

// Rotates \`v\` by the unit quaternion \`q = (x, y, z, w)\`.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// An instance record's position in 1/128 voxel (record words 0 and 1).
fn record_position(dx: u32, dy: u32) -> vec3<u32> {
    return vec3<u32>(dx & 0x1FFFFFu, (dx >> 21u) | (((dy >> 21u) & 0xFFu) << 11u), dy & 0x1FFFFFu);
}

// An instance record's entity id (record word 4).
fn record_id(e: u32) -> u32 {
    return e & 0x3FFFu;
}

// Tests the instance record at word \`at\` against the ray; keeps the nearest entity hit.
fn test_instance(r: Ray, at: u32, t_lo: f32) {
    let dx = instance_word(at);
    let dy = instance_word(at + 1u);
    let dz = instance_word(at + 2u);
    let dw = instance_word(at + 3u);
    let e = instance_word(at + 4u);
    let id = record_id(e);
    let size = vec3<u32>((e >> 14u) & 0x7Fu, (e >> 21u) & 0x7Fu, ((e >> 28u) & 0xFu) | (((dy >> 29u) & 7u) << 4u));
    let pos = record_position(dx, dy);
    var limit = T_INF;
    var equal_ok = false;
    if best_entity.hit {
        limit = best_entity.t;
        equal_ok = id < best_entity.entity;
    }
    // The entity lies within |size| of its local-origin corner: reject rays that pass
    // farther (with slack for f32), before transforming anything.
    let rel = vec3<f32>(r.o_int - vec3<i32>(pos >> vec3<u32>(7u))) + (r.o_frac - vec3<f32>(pos & vec3<u32>(127u)) / 128.0);
    let tc = -dot(rel, r.d) / (r.len * r.len);
    let radius = (length(vec3<f32>(size)) + 0.01) / r.len;
    let closest = rel + r.d * tc;
    if dot(closest, closest) > radius * radius * r.len * r.len || tc + radius < t_lo || tc - radius > limit {
        return;
    }
    let q = decode_quat(dz, dw & 0xFFFu);
    let local = ray_from(rotate(q, rel), rotate(q, r.d));
    let isize = vec3<i32>(size);
    let entry = ray_entry(local, isize);
    if !entry.ok {
        return;
    }
    let base = (dw >> 12u) * TYPE_ALIGN;
    var s = dda_start(local, entry);
    loop {
        entity_steps += 1u;
        if s.t > limit || (s.t == limit && !equal_ok) {
            return;
        }
        if s.t >= t_lo {
            let c = vec3<u32>(s.cell);
            let v = entity_type_word(base + c.x + size.x * (c.y + size.y * c.z));
            if (v & ENTITY_SOLID) != 0u {
                var h = make_hit(local, s.cell, s.t, s.axis, v & MAX_MATERIAL, 0u);
                h.entity = id;
                best_entity = h;
                best_rotation = q;
                return;
            }
        }
        dda_advance(local, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= isize) {
            return;
        }
    }
}

// The world-space normal of the hit the last \`trace\` returned (entity-local normals are
// rotated back to the world).
fn world_normal(h: Hit) -> vec3<f32> {
    let n = vec3<f32>(h.normal);
    if !hit_instance {
        return n;
    }
    return rotate(conjugate(best_rotation), n);
}

// Clears the entity state of the last trace and runs the world loop: how a trace starts.
fn world_first(r: Ray) -> WorldTrace {
    entity_steps = 0u;
    best_entity = no_hit(0u);
    hit_instance = false;
    return world_loop(r);
}

// Traces \`r\` through the world and its entities.
fn trace(r: Ray) -> Hit {
    let w = world_first(r);
    if w.end == END_MISSED || w.end == END_EXHAUSTED {
        return w.hit;
    }
    find_instances(r, w.t_entry, w.t_end, false);
    if best_entity.hit && best_entity.t < w.t_end {
        hit_instance = true;
        var h = best_entity;
        h.steps = w.hit.steps + entity_steps;
        return h;
    }
    var h = w.hit;
    h.steps += entity_steps;
    return h;
}

// Whether \`trace(r)\` would hit (\`x\`) and whether it would run out of steps (\`y\`), for rays
// that only ask whether something is in the way (shadow rays): a ray that hits the world
// needs no instance walk, and one that leaves it stops walking at the first instance hit.
fn occlusion(r: Ray) -> vec2<bool> {
    let w = world_first(r);
    if w.end != END_LEFT {
        return vec2<bool>(w.hit.hit, w.hit.exhausted);
    }
    find_instances(r, w.t_entry, w.t_end, true);
    return vec2<bool>(best_entity.hit && best_entity.t < w.t_end, false);
}

// The world loop over the chunk → block → voxel hierarchy (docs/NAADF.md §9), with
// AADF jumps (\`USE_AADF\`, the \`naadf\` method) or without (\`nodf\`): the GPU twin of
// world/src/traverse/hierarchy.rs. It sees the static world alone: entities are found
// afterwards, through their hierarchy (trace.wgsl).

override USE_AADF: bool = true;
// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;


fn to_edge(c: u32, neg: bool, edge: u32) -> i32 {
    let m = c & (edge - 1u);
    return i32(select(edge - 1u - m, m, neg));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing = vec3<u32>(0u, 2u, 4u) + select(vec3<u32>(0u), vec3<u32>(1u), r.d > vec3<f32>(0.0));
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(cell);
        let chunk = chunk_word(chunk_index(p >> vec3<u32>(4u), chunks));
        var skip = vec3<i32>(0);
        let cs = cell_state(chunk);
        if cs == STATE_FULL {
            return WorldTrace(make_hit(r, cell, t, axis, chunk & MAX_MATERIAL, steps), END_HIT, entry.t, t);
        } else if cs == STATE_EMPTY {
            for (var a = 0u; a < 3u; a++) {
                skip[a] = to_edge(p[a], neg[a], 16u);
                if USE_AADF {
                    skip[a] += 16 * i32(aadf_field(chunk, facing[a], CHUNK_FIELD_BITS));
                }
            }
        } else {
            let block = block_word((chunk & PAYLOAD) + index4((p >> vec3<u32>(2u)) & vec3<u32>(3u)));
            let bs = cell_state(block);
            if bs == STATE_FULL {
                return WorldTrace(make_hit(r, cell, t, axis, block & MAX_MATERIAL, steps), END_HIT, entry.t, t);
            } else if bs == STATE_EMPTY {
                for (var a = 0u; a < 3u; a++) {
                    skip[a] = to_edge(p[a], neg[a], 4u);
                    if USE_AADF {
                        skip[a] += 4 * i32(aadf_field(block, facing[a], CELL_FIELD_BITS));
                    }
                }
            } else {
                let v = group_voxel(block & PAYLOAD, index4(p & vec3<u32>(3u)));
                if (v & VOXEL_SOLID) != 0u {
                    return WorldTrace(make_hit(r, cell, t, axis, v & MAX_MATERIAL, steps), END_HIT, entry.t, t);
                }
                if USE_AADF {
                    for (var a = 0u; a < 3u; a++) {
                        skip[a] = i32(aadf_field(v, facing[a], CELL_FIELD_BITS));
                    }
                }
            }
        }
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            // An AADF box may reach beyond the world: the ray left it at the world's edge.
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, min(ex.t, leave_time(r, dims)));
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

// The samples of the lit passes: random streams (client/src/light/rng.rs), one per sample
// of each pixel, seeded from the run's seed, the pixel's index and the sample's number
// only; and the jittered camera ray of a sample.

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The stream of sample \`sample\` of pixel \`pixel\` under \`seed\`.
fn rng_new(seed: u32, pixel: u32, sample: u32) -> u32 {
    return pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(sample)));
}

// A uniform number in [0, 1) with 24 random bits.
fn rng_next(state: ptr<function, u32>) -> f32 {
    *state = pcg_hash(*state);
    return f32(*state >> 8u) * (1.0 / 16777216.0);
}

// The stream of sample \`sample\` of pixel \`pixel\`, after its first two draws: where in the
// pixel the sample's camera ray goes (uniform in [0, 1)²).
struct PixelStream {
    rng: u32,
    jitter: vec2<f32>,
}

fn pixel_stream(seed: u32, pixel: u32, sample: u32) -> PixelStream {
    var rng = rng_new(seed, pixel, sample);
    let jx = rng_next(&rng);
    let jy = rng_next(&rng);
    return PixelStream(rng, vec2<f32>(jx, jy));
}

// The camera's (unnormalised) direction through point \`jitter\` ([0, 1)²) of pixel \`gid\` of
// frame \`f\` (docs/CAMERA.md, with \`px + jitter.x\` for \`px + 0.5\`).
fn camera_dir(f: FrameInfo, gid: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let sx = 2.0 * (f32(gid.x) + jitter.x) / f32(f.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + jitter.y) / f32(f.height);
    return f.forward + sx * f.right + sy * f.up;
}

// The light model of the lit modes (docs/RENDERING.md §3a): the physical sky, the sun,
// BRDF sampling and one path's radiance. The GPU twin of client/src/light/ (sky.rs,
// scatter.rs, cpu.rs), written operation by operation like it so that the two path
// tracers agree up to rounding. Needs random.wgsl before it.
//
// The pass binds \`light: LightInfo\` (generated in the prelude from the Rust \`LightInfo\`),
// and declares \`DIFFUSE_TIER\` and \`diffuse_tier\` (no_tier.wgsl, or a lighting tier such as
// roma.wgsl) for \`path_step\`.

// PI, SURFACE_OFFSET (how far scattered and shadow rays start off the surface),
// MIN_ALPHA (the smallest GGX α a metal is traced with) and the physical sky's constants
// (PLANET_RADIUS, VIEW_STEPS, RAYLEIGH, MIE_G, OZONE, …) come from the prelude, generated
// from their Rust definitions in client/src/light/ (mod.rs, scatter.rs, sky.rs).

// ---- The physical sky (sky.rs) ----

// Distance from height \`h\` along zenith cosine \`mu\` to the sphere at height \`top\`; a
// negative value when it is not reached going forward.
fn sphere_distance(h: f32, mu: f32, top: f32) -> f32 {
    let r = PLANET_RADIUS + h;
    let disc = (top - h) * (2.0 * PLANET_RADIUS + top + h) + r * r * mu * mu;
    if disc < 0.0 {
        return -1.0;
    }
    let s = sqrt(disc);
    let far = -r * mu + s;
    if far < 0.0 {
        return -1.0;
    }
    let near = -r * mu - s;
    return select(far, near, near > 0.0);
}

struct Medium {
    sigma: vec3<f32>,
    rayleigh: f32,
    mie: f32,
}

fn medium(h: f32) -> Medium {
    let rayleigh = exp(-h / RAYLEIGH_SCALE);
    let mie = exp(-h / MIE_SCALE);
    let ozone = max(1.0 - abs(h - OZONE_CENTRE) / OZONE_HALF_WIDTH, 0.0);
    return Medium(RAYLEIGH * rayleigh + MIE_EXTINCTION * mie + OZONE * ozone, rayleigh, mie);
}

fn sun_transmittance(h: f32, mu: f32) -> vec3<f32> {
    if mu < 0.0 && sphere_distance(h, mu, 0.0) >= 0.0 {
        return vec3<f32>(0.0);
    }
    let length = max(sphere_distance(h, mu, ATMOSPHERE_HEIGHT), 0.0);
    let dt = length / f32(LIGHT_STEPS);
    let r = PLANET_RADIUS + h;
    var depth = vec3<f32>(0.0);
    for (var i = 0u; i < LIGHT_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let hi = sqrt(t * t + 2.0 * r * mu * t + r * r) - PLANET_RADIUS;
        depth += medium(hi).sigma * dt;
    }
    return exp(-depth);
}

// Sky radiance along unit \`dir\` for unit sun direction \`sun\`, per unit of irradiance.
fn sky_physical(dir: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let mu = dir.y;
    let nu = dot(dir, sun);
    let h0 = EYE_HEIGHT;
    let r0 = PLANET_RADIUS + h0;
    var length = sphere_distance(h0, mu, 0.0);
    if !(mu < 0.0 && length >= 0.0) {
        length = max(sphere_distance(h0, mu, ATMOSPHERE_HEIGHT), 0.0);
    }
    let dt = length / f32(VIEW_STEPS);
    let phase_r = 3.0 / (16.0 * PI) * (1.0 + nu * nu);
    let g2 = MIE_G * MIE_G;
    let phase_m = (1.0 - g2) / (4.0 * PI * pow(1.0 + g2 - 2.0 * MIE_G * nu, 1.5));
    var depth = vec3<f32>(0.0);
    var inscatter = vec3<f32>(0.0);
    for (var i = 0u; i < VIEW_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let r = sqrt(t * t + 2.0 * r0 * mu * t + r0 * r0);
        let h = r - PLANET_RADIUS;
        let mu_sun = (r0 * sun.y + t * nu) / r;
        let m = medium(h);
        let to_sun = sun_transmittance(h, mu_sun);
        let view = exp(-(depth + 0.5 * m.sigma * dt));
        let scatter = RAYLEIGH * m.rayleigh * phase_r + MIE_SCATTER * m.mie * phase_m;
        inscatter += view * to_sun * scatter * dt;
        depth += m.sigma * dt;
    }
    return inscatter;
}

// The sky along unit \`d\`, evaluated directly (no disc).
fn sky_direct(d: vec3<f32>) -> vec3<f32> {
    if light.sky_physical != 0u {
        return sky_physical(d, light.sun_dir) * light.sky;
    }
    return light.sky;
}

// The sky along unit \`d\`; with \`disc\`, the sun's disc too. \`sky_base(d)\` is the including
// pass's choice: \`sky_direct\` (the path tracer) or the atmosphere table (\`gi\`).
fn sky_radiance(d: vec3<f32>, disc: bool) -> vec3<f32> {
    var l = sky_base(d);
    if disc {
        l += sun_disc(d);
    }
    return l;
}

// The sun's disc along unit \`d\` (0 off the disc, or with the sun off).
fn sun_disc(d: vec3<f32>) -> vec3<f32> {
    if light.sun_on != 0u && 1.0 - dot(d, light.sun_dir) <= light.sun_omc {
        return vec3<f32>(light.sun_disc);
    }
    return vec3<f32>(0.0);
}

// ---- Scattering (scatter.rs) ----

struct Basis {
    t: vec3<f32>,
    b: vec3<f32>,
}

fn basis(n: vec3<f32>) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

fn sample_cosine(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let f = basis(n);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (r * cos(phi)) + f.b * (r * sin(phi)) + n * sqrt(max(1.0 - u.x, 0.0)));
}

fn sample_cone(axis: vec3<f32>, omc: f32, u: vec2<f32>) -> vec3<f32> {
    let f = basis(axis);
    let x = u.x * omc;
    let c = 1.0 - x;
    let s = sqrt(max(x * (2.0 - x), 0.0));
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (s * cos(phi)) + f.b * (s * sin(phi)) + axis * c);
}

fn schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let k = 1.0 - clamp(c, 0.0, 1.0);
    let k2 = k * k;
    return f0 + (vec3<f32>(1.0) - f0) * (k2 * k2 * k);
}

fn smith_lambda(alpha: f32, c: f32) -> f32 {
    let c2 = max(c * c, 1e-12);
    let tan2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (-1.0 + sqrt(1.0 + alpha * alpha * tan2));
}

fn ggx_d(alpha: f32, c: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = c * c * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

fn ggx(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, alpha: f32, f0: vec3<f32>) -> vec3<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if co <= 0.0 || ci <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = normalize(wo + wi);
    let g2 = 1.0 / (1.0 + smith_lambda(alpha, co) + smith_lambda(alpha, ci));
    return schlick(f0, dot(wo, h)) * (ggx_d(alpha, dot(n, h)) * g2 / (4.0 * co * ci));
}

struct Scattered {
    dir: vec3<f32>,
    weight: vec3<f32>,
}

fn ggx_sample(n: vec3<f32>, wo: vec3<f32>, alpha: f32, f0: vec3<f32>, u: vec2<f32>) -> Scattered {
    let f = basis(n);
    let v = vec3<f32>(dot(wo, f.t), dot(wo, f.b), dot(wo, n));
    let vh = normalize(vec3<f32>(alpha * v.x, alpha * v.y, v.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = t1 * p1 + t2 * p2 + vh * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    let m = normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    let lwi = m * (2.0 * dot(v, m)) - v;
    let wi = normalize(f.t * lwi.x + f.b * lwi.y + n * lwi.z);
    let lo = smith_lambda(alpha, v.z);
    let li = smith_lambda(alpha, lwi.z);
    return Scattered(wi, schlick(f0, dot(v, m)) * ((1.0 + lo) / (1.0 + lo + li)));
}

// ---- Paths (cpu.rs) ----

// Whether a shadow ray meets anything before leaving the world (a ray out of cells counts
// as blocked).
fn blocked(r: Ray, p: vec3<f32>, dir: vec3<f32>) -> bool {
    return any(occlusion(ray_at(r, p, dir)));
}

// One sample of the sun's disc seen from \`p\` (relative to \`r\`'s integer origin, just off a
// surface of normal \`n\`): its direction, and the irradiance it brings (\`E·cosθ\`-weighted)
// when it is above the surface and unblocked, else 0. Two random numbers are drawn
// whenever the sun is on (cpu.rs \`sun_sample\`).
struct SunSample {
    dir: vec3<f32>,
    irradiance: f32,
}

fn sun_sample(r: Ray, p: vec3<f32>, n: vec3<f32>, rng: ptr<function, u32>) -> SunSample {
    if light.sun_on == 0u {
        return SunSample(vec3<f32>(0.0), 0.0);
    }
    let u = vec2<f32>(rng_next(rng), rng_next(rng));
    let wi = sample_cone(light.sun_dir, light.sun_omc, u);
    let c = dot(n, wi);
    if c > 0.0 && !blocked(r, p, wi) {
        return SunSample(wi, c * light.sun_weight);
    }
    return SunSample(wi, 0.0);
}

// One step of a path: what it adds and whether it goes on.
struct PathState {
    r: Ray,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    sees_disc: bool,
    alive: bool,
    // The normal of the first surface met (zero until then).
    first_normal: vec3<f32>,
}

// Follows the path in \`s\` to its next surface: adds the light found there and, when
// \`scatter\`, picks the next ray (or ends the path). Returns the distance to the surface
// (−1 when the ray found none).
fn path_step(s: ptr<function, PathState>, scatter: bool, rng: ptr<function, u32>) -> f32 {
    let r = (*s).r;
    let h = trace(r);
    let d = r.d / r.len;
    (*s).alive = false;
    if h.exhausted {
        return -1.0;
    }
    if !h.hit {
        (*s).radiance += (*s).throughput * sky_radiance(d, (*s).sees_disc);
        return -1.0;
    }
    let distance = h.t * r.len;
    if h.axis == NO_AXIS {
        return distance;
    }
    // Before any other trace: world_normal reads the last trace's entity rotation.
    let n = world_normal(h);
    if all((*s).first_normal == vec3<f32>(0.0)) {
        (*s).first_normal = n;
    }
    let m = material(h.material);
    if m.kind == KIND_EMISSIVE {
        (*s).radiance += (*s).throughput * m.albedo * m.emission;
    }
    // A lighting tier (\`roma\`, \`irradiance\`) lights diffuse and emissive surfaces itself,
    // and the path ends there; mirrors and metals scatter on.
    if DIFFUSE_TIER && m.kind != KIND_MIRROR && m.kind != KIND_METAL {
        let surface = vec3<f32>(r.o_int) + ray_local(r, h.t);
        (*s).radiance += (*s).throughput * diffuse_tier(h, surface, n, m.albedo, rng);
        return distance;
    }
    if !scatter {
        return distance;
    }
    let p = ray_local(r, h.t) + n * SURFACE_OFFSET;
    var next: Scattered;
    if m.kind == KIND_MIRROR {
        (*s).sees_disc = true;
        next = Scattered(d - n * (2.0 * dot(d, n)), m.albedo);
    } else {
        let wo = -d;
        let alpha = max(m.roughness, MIN_ALPHA);
        let sun = sun_sample(r, p, n, rng);
        if sun.irradiance > 0.0 {
            var f = m.albedo / PI;
            if m.kind == KIND_METAL {
                f = ggx(n, wo, sun.dir, alpha, m.albedo);
            }
            (*s).radiance += (*s).throughput * f * sun.irradiance;
        }
        let u = vec2<f32>(rng_next(rng), rng_next(rng));
        (*s).sees_disc = false;
        if m.kind == KIND_METAL {
            next = ggx_sample(n, wo, alpha, m.albedo, u);
        } else {
            next = Scattered(sample_cosine(n, u), m.albedo);
        }
    }
    if dot(next.dir, n) > 0.0 {
        (*s).throughput *= next.weight;
        (*s).r = ray_at(r, p, next.dir);
        (*s).alive = true;
    }
    return distance;
}

// One path: the radiance it brought back, the distance from its origin to the first
// surface (−1 for the sky) and that surface's normal.
struct PathSample {
    radiance: vec3<f32>,
    distance: f32,
    normal: vec3<f32>,
}

// The radiance arriving along \`primary\` when the path may scatter \`bounces\` more times,
// drawing from \`rng\`. \`sees_disc\`: whether the ray sees the sun's disc (camera and mirror
// rays do; rays scattered by other surfaces get the sun by next-event estimation instead).
fn path_radiance(primary: Ray, bounces: u32, sees_disc: bool, rng: ptr<function, u32>) -> PathSample {
    var s = PathState(primary, vec3<f32>(0.0), vec3<f32>(1.0), sees_disc, true, vec3<f32>(0.0));
    let distance = path_step(&s, bounces > 0u, rng);
    for (var bounce = 1u; bounce <= bounces && s.alive; bounce++) {
        path_step(&s, bounce < bounces, rng);
    }
    return PathSample(s.radiance, distance, s.first_normal);
}

// No lighting tier: \`path_step\` (light.wgsl) traces diffuse surfaces as the light model
// does. Included by the path tracer, the GI passes and the irradiance cache's updates;
// \`roma\` and \`irradiance\` include roma.wgsl and irradiance.wgsl instead.

const DIFFUSE_TIER: bool = false;

fn diffuse_tier(h: Hit, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// The first-hit chain shared by \`albedo\` (render.wgsl) and \`gi\` (gi_primary.wgsl): a camera
// ray followed through up to MAX_SEGMENTS − 1 mirror bounces to the first surface that is
// not a mirror, with the bounce planes of the reference's first-hit record
// (docs/RENDERING.md §2, §3c).

// Hit-plane sentinels of the first-hit record (docs/NAADF.md §10).
const HIT_NOTHING: u32 = 0x1FFFFu;
const HIT_UNDEFINED: u32 = 0u;
// Mirror segments a path may follow (the primary segment included).
const MAX_SEGMENTS: u32 = 4u;
// Secondary-ray origins start SURFACE_OFFSET off the surface, along its normal
// (docs/NAADF.md §12; from the prelude).

// How a chain ended.
const CHAIN_SURFACE: u32 = 0u;
const CHAIN_SKY: u32 = 1u;
// The last segment allowed met a mirror too.
const CHAIN_LIMIT: u32 = 2u;

// The 17-bit hit plane: normal id (1 −x, 2 +x, 3 −y, 4 +y, 5 −z, 6 +z; 7 = origin inside
// the voxel) in bits 0–2, the plane's integer coordinate in bits 3–16.
fn encode_plane(h: Hit) -> u32 {
    if h.axis == NO_AXIS {
        return 7u;
    }
    let positive = h.normal[h.axis] > 0;
    let id = 2u * h.axis + select(1u, 2u, positive);
    let coord = u32(h.voxel[h.axis] + select(0, 1, positive)) & 0x3FFFu;
    return id | (coord << 3u);
}

struct Chain {
    // The last segment and what it met (\`h.hit\` is false for the sky).
    r: Ray,
    h: Hit,
    // The final surface's world normal (read right after its trace: world_normal reads the
    // entity rotation of the last trace).
    n: vec3<f32>,
    // The product of the mirror weights along the chain.
    throughput: vec3<f32>,
    planes: array<u32, 4>,
    // Path length to the final surface; −1 for the sky and the mirror limit.
    distance: f32,
    end: u32,
}

// Follows \`primary\` (whose first hit is \`first\`) through mirrors. A mirror weighs the path
// by Schlick's Fresnel with F0 = albedo when \`schlick\`, by its albedo otherwise (the light
// model's tinted mirror, docs/RENDERING.md §3a).
fn first_hit_chain(primary: Ray, first: Hit, schlick: bool) -> Chain {
    var c = Chain(primary, first, vec3<f32>(0.0), vec3<f32>(1.0),
        array<u32, 4>(HIT_UNDEFINED, HIT_UNDEFINED, HIT_UNDEFINED, HIT_UNDEFINED), 0.0, CHAIN_SURFACE);
    for (var seg = 0u; seg < MAX_SEGMENTS; seg++) {
        if seg > 0u {
            c.h = trace(c.r);
        }
        let dn = c.r.d / c.r.len;
        if !c.h.hit {
            c.planes[seg] = HIT_NOTHING;
            c.distance = -1.0;
            c.end = CHAIN_SKY;
            return c;
        }
        c.planes[seg] = encode_plane(c.h);
        c.distance += c.h.t * c.r.len;
        c.n = world_normal(c.h);
        let m = material(c.h.material);
        if m.kind != KIND_MIRROR {
            return c;
        }
        if seg + 1u == MAX_SEGMENTS {
            c.planes[seg] = HIT_NOTHING;
            c.distance = -1.0;
            c.end = CHAIN_LIMIT;
            return c;
        }
        if schlick {
            let cos_i = clamp(-dot(c.n, dn), 0.0, 1.0);
            c.throughput *= m.albedo + (1.0 - m.albedo) * pow(1.0 - cos_i, 5.0);
        } else {
            c.throughput *= m.albedo;
        }
        let p = ray_local(c.r, c.h.t) + c.n * SURFACE_OFFSET;
        c.r = ray_at(c.r, p, reflect(dn, c.n));
    }
    return c;
}

// The GI pipeline (\`gi\`, docs/RENDERING.md §3c): bindings and helpers shared by its passes
// (gi_primary.wgsl, gi_samples.wgsl, gi_resample.wgsl). Every pass binds the same group 1;
// the constants in capitals without a definition here (TAA_SLOTS, CAMERA_HISTORY, CAM_WORDS,
// the control words CONTROL_*, …) are generated after the GI files from their Rust
// definitions in client/src/gpu/gi/memory.rs.

@group(1) @binding(0) var<uniform> frame: FrameInfo;
@group(1) @binding(1) var<uniform> light: LightInfo;
@group(1) @binding(2) var<uniform> gi: GiInfo;
// The pipeline's memory (docs/RENDERING.md §3c). The GI's arrays live in four logical
// buffers, each array at an offset that \`gi\` carries (computed in gi.rs). \`words\` and
// \`buckets\` are bound here; \`mem\` and \`taa\` can outgrow one binding of the adapter, so the
// generated declarations after the GI files split each across bindings (from binding 6)
// and give their accessors: \`mem_get(i)\`, \`mem_set(i, v)\`, \`taa_get(i)\`, \`taa_set(i, v)\`.
// - \`mem\` (vec4 words; f32 data is stored bitcast):
//   - cams: CAMERA_HISTORY cameras, newest first (index = frames ago), CAM_WORDS each:
//     (position relative to this frame's integer camera position, jitter x), (forward,
//     jitter y), (right, 0), (up, 0), (that frame's integer position minus this one's, 0);
//   - lut: the atmosphere table, LUT_SIZE² latitude–longitude texels of sky radiance;
//   - gbuf, per pixel: the final surface of the first-hit chain relative to the integer
//     camera position, and the chain's length (−1: sky or mirror limit);
//   - gmat, per pixel: x = kind | class << 4 | normal id << 8 | material << 16;
//     y = TAA hash (16 bits) | octahedral normal << 16; z, w = the chain's throughput
//     (f16 r, g | b) with the octahedral outgoing direction in w's high half;
//   - emitted, per pixel: the light the first-hit chain met (sky, sun disc, emission);
//   - taa_info, per pixel, 2 vec4: the accepted history samples' colour sum and count;
//     the least and greatest chain length of the 3×3 neighbourhood (sky: SKY_DIST);
//   - illum, illum2, per pixel: the surface's incoming light before the chain's
//     throughput, and the denoiser's guide (illum2: the denoiser's intermediate);
//   - result, per pixel: the frame's linear radiance after the TAA merge;
//   - refined, per region: MAX_KEPT refined samples, 2 vec4 each;
//   - region_info, per region, 3 vec4: the lit ratio per normal id (0–3), (lit ratio of
//     ids 4 and 5, samples kept, samples projected) and (normal mask, least and greatest
//     chain length, 0);
//   - ring: the sample ring, RING_VEC4 vec4 per secondary sample (gi_samples.wgsl).
// - \`words\`: the control words (indirect arguments at CONTROL_TRACE_ARGS and
//   CONTROL_PROJECT_ARGS, ring bookkeeping, per-frame sample counts), then per region the
//   queued count and (at R + region) the queue offset, then per region 64 queued pixels.
// - \`buckets\`: per region BUCKET_SLOTS priorities, BUCKET_SLOTS ring indices, then the
//   lit and unlit counts of each normal id (2 × NORMALS words).
// - \`taa\`: the long-term TAA, TAA_SLOTS frames of 64-bit samples.
@group(1) @binding(3) var<storage, read_write> words: array<u32>;
@group(1) @binding(4) var<storage, read_write> buckets: array<atomic<u32>>;
// Per chunk (\`chunk_index\`): the first frame after its newest change, and after the newest
// change within CHANGE_REACH chunks of it (0: none); written by gi.rs from the world's
// changed chunks.
@group(1) @binding(5) var<storage, read> changes: array<vec2<u32>>;

// The chain length of the sky in the TAA (the largest finite f16).
const SKY_DIST: f32 = 65504.0;
// Kinds of final surface (gmat.x bits 4–7).
const CLASS_DIFFUSE: u32 = 0u;
const CLASS_GLOSSY: u32 = 1u;
const CLASS_NONE: u32 = 2u;
const NO_NORMAL: u32 = 7u;
// Normal ids of surfaces (0–5).
const NORMALS: u32 = 6u;

fn pixel_count() -> u32 {
    return frame.width * frame.height;
}

fn region_count() -> u32 {
    return gi.regions_x * gi.regions_y;
}

fn taa_accum(i: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(mem_get(gi.off_taa_info + 2u * i));
}

fn taa_range(i: u32) -> vec2<f32> {
    return bitcast<vec4<f32>>(mem_get(gi.off_taa_info + 2u * i + 1u)).xy;
}

// The unit vector of normal id \`id\`.
fn normal_of_id(id: u32) -> vec3<f32> {
    let sign = select(-1.0, 1.0, (id & 1u) == 1u);
    return vec3<f32>(select(0.0, sign, id / 2u == 0u), select(0.0, sign, id / 2u == 1u), select(0.0, sign, id / 2u == 2u));
}

// The change marks (\`changes\`) of the chunk holding the solid voxel behind surface point
// \`p\` (relative to this frame's integer camera position) of normal \`n\`; none outside the
// world.
fn changes_at(p: vec3<f32>, n: vec3<f32>) -> vec2<u32> {
    let v = floor(vec3<f32>(frame.cam_int) + p - 0.5 * n);
    if any(v < vec3<f32>(0.0)) || any(v >= vec3<f32>(world_info.size)) {
        return vec2<u32>(0u);
    }
    return changes[chunk_index(vec3<u32>(v) / 16u, world_info.chunks)];
}

fn region_of(x: u32, y: u32) -> u32 {
    return x / 8u + (y / 8u) * gi.regions_x;
}

// ---- Cameras of earlier frames ----

struct Cam {
    pos: vec3<f32>,
    jitter: vec2<f32>,
    forward: vec3<f32>,
    right: vec3<f32>,
    up: vec3<f32>,
    origin: vec3<f32>,
}

// The thread's index in a dispatch of 64-wide groups laid out as x + y · (groups across)
// (\`dispatch_2d\` on the host, or the queue scan's indirect arguments).
fn flat_id(wid: vec3<u32>, groups: vec3<u32>, li: u32) -> u32 {
    return (wid.x + wid.y * groups.x) * 64u + li;
}

// Earlier frames whose cameras \`cams\` holds: every one, up to CAMERA_HISTORY − 1.
fn cams_valid() -> u32 {
    return min(gi.frame, CAMERA_HISTORY - 1u);
}

fn cam(age: u32) -> Cam {
    let b = min(age, CAMERA_HISTORY - 1u) * CAM_WORDS;
    let a = bitcast<vec4<f32>>(mem_get(b));
    let f = bitcast<vec4<f32>>(mem_get(b + 1u));
    return Cam(a.xyz, vec2<f32>(a.w, f.w), f.xyz, bitcast<vec4<f32>>(mem_get(b + 2u)).xyz, bitcast<vec4<f32>>(mem_get(b + 3u)).xyz, bitcast<vec4<f32>>(mem_get(b + 4u)).xyz);
}

// Whether two cameras see exactly the same view (position, orientation and field of view;
// their jitters may differ).
fn same_view(a: Cam, b: Cam) -> bool {
    return all(a.pos == b.pos) && all(a.origin == b.origin) && all(a.forward == b.forward)
        && all(a.right == b.right) && all(a.up == b.up);
}

// Where \`v\` (relative to the camera) falls on camera \`c\`'s image, in pixels from its
// top-left corner; \`z\` ≤ 0 when behind it.
struct Projection {
    px: vec2<f32>,
    z: f32,
}

fn project(c: Cam, v: vec3<f32>) -> Projection {
    let z = dot(v, c.forward);
    if z <= 0.0 {
        return Projection(vec2<f32>(-1.0), z);
    }
    let sx = dot(v, c.right) / (z * dot(c.right, c.right));
    let sy = dot(v, c.up) / (z * dot(c.up, c.up));
    return Projection(vec2<f32>((sx + 1.0) * 0.5 * f32(frame.width), (1.0 - sy) * 0.5 * f32(frame.height)), z);
}

fn on_image(p: vec2<f32>) -> bool {
    return all(p >= vec2<f32>(0.0)) && p.x < f32(frame.width) && p.y < f32(frame.height);
}

// The camera ray of pixel \`q\` of camera \`c\` through its jittered point.
fn cam_dir(c: Cam, q: vec2<u32>) -> vec3<f32> {
    let sx = 2.0 * (f32(q.x) + c.jitter.x) / f32(frame.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(q.y) + c.jitter.y) / f32(frame.height);
    return c.forward + sx * c.right + sy * c.up;
}

// ---- Encodings ----

// Normal id: 2·axis + (1 when positive) for the dominant axis.
fn normal_id(n: vec3<f32>) -> u32 {
    let a = abs(n);
    var axis = 2u;
    if a.x >= a.y && a.x >= a.z {
        axis = 0u;
    } else if a.y >= a.z {
        axis = 1u;
    }
    return 2u * axis + select(0u, 1u, n[axis] > 0.0);
}

// A unit vector in 16 bits (octahedral, 8 bits a component, on 255 levels so that 0 and
// ±1 are exact: the world's axis normals survive unchanged).
fn oct_encode(n: vec3<f32>) -> u32 {
    var p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z < 0.0 {
        p = (vec2<f32>(1.0) - abs(p.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), p >= vec2<f32>(0.0));
    }
    let q = vec2<u32>(round(clamp(p * 0.5 + 0.5, vec2<f32>(0.0), vec2<f32>(1.0)) * 254.0));
    return q.x | (q.y << 8u);
}

fn oct_decode(e: u32) -> vec3<f32> {
    let p = vec2<f32>(f32(e & 0xFFu), f32((e >> 8u) & 0xFFu)) / 254.0 * 2.0 - 1.0;
    var n = vec3<f32>(p, 1.0 - abs(p.x) - abs(p.y));
    if n.z < 0.0 {
        let xy = (vec2<f32>(1.0) - abs(n.yx)) * select(vec2<f32>(-1.0), vec2<f32>(1.0), n.xy >= vec2<f32>(0.0));
        n = vec3<f32>(xy, n.z);
    }
    return normalize(n);
}

// The pixel's final surface: its normal (from gmat.y) and material (gmat.x).
fn surface_normal(g: vec4<u32>) -> vec3<f32> {
    return oct_decode(g.y >> 16u);
}

fn surface_class(g: vec4<u32>) -> u32 {
    return (g.x >> 4u) & 3u;
}

fn surface_normal_id(g: vec4<u32>) -> u32 {
    return (g.x >> 8u) & 7u;
}

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3<f32>(0.2126, 0.7152, 0.0722));
}

// ---- The atmosphere table ----

// The table is latitude–longitude: columns are azimuth, rows elevation warped as
// v = sign(e)·sqrt(|e|/(π/2)) to spend rows near the horizon, which lies exactly between
// rows LUT_SIZE/2 − 1 and LUT_SIZE/2, so that no lookup blends the sky with the ground.

// The table coordinates (continuous, texel centres at +0.5) of unit \`d\`.
fn lut_coords(d: vec3<f32>) -> vec2<f32> {
    let e = asin(clamp(d.y, -1.0, 1.0)) / (0.5 * PI);
    let v = sign(e) * sqrt(abs(e));
    let a = atan2(d.x, d.z) / (2.0 * PI) + 0.5;
    return vec2<f32>(a, v * 0.5 + 0.5) * f32(LUT_SIZE);
}

// The unit direction at the centre of texel \`t\`.
fn lut_direction(t: vec2<u32>) -> vec3<f32> {
    let uv = (vec2<f32>(t) + 0.5) / f32(LUT_SIZE);
    let v = uv.y * 2.0 - 1.0;
    let e = sign(v) * v * v * 0.5 * PI;
    let a = (uv.x - 0.5) * 2.0 * PI;
    return vec3<f32>(cos(e) * sin(a), sin(e), cos(e) * cos(a));
}

// Texel (x, y) with x wrapping around the azimuth and y clamped to the rows of the
// hemisphere \`upper\` names.
fn lut_texel(x: i32, y: i32, upper: bool) -> vec3<f32> {
    let half = i32(LUT_SIZE) / 2;
    let cx = u32((x + i32(LUT_SIZE)) % i32(LUT_SIZE));
    let cy = u32(select(clamp(y, 0, half - 1), clamp(y, half, i32(LUT_SIZE) - 1), upper));
    return bitcast<vec4<f32>>(mem_get(gi.off_lut + cx + cy * LUT_SIZE)).rgb;
}

// The sky along unit \`d\` from the table, bilinearly filtered within its hemisphere.
fn sky_base(d: vec3<f32>) -> vec3<f32> {
    if light.sky_physical == 0u {
        return light.sky;
    }
    let upper = d.y >= 0.0;
    let t = lut_coords(d) - 0.5;
    let b = floor(t);
    let f = t - b;
    let x = i32(b.x);
    let y = i32(b.y);
    let top = mix(lut_texel(x, y, upper), lut_texel(x + 1, y, upper), f.x);
    let bottom = mix(lut_texel(x, y + 1, upper), lut_texel(x + 1, y + 1, upper), f.x);
    return mix(top, bottom, f.y);
}

// Pass \`gi_atmosphere\`: fills the whole table (when a history starts: the light is part of
// what a history is of).
@compute @workgroup_size(8, 8)
fn gi_atmosphere(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= LUT_SIZE || gid.y >= LUT_SIZE {
        return;
    }
    mem_set(gi.off_lut + gid.x + gid.y * LUT_SIZE, bitcast<vec4<u32>>(vec4<f32>(sky_direct(lut_direction(gid.xy)), 0.0)));
}

// The entities' poses per frame, so that the long-term TAA follows a moving entity
// (docs/RENDERING.md §3c, "Entities in the history").
//
// \`words\` holds, after the queued pixels, TAA_SLOTS tables of ENTITY_IDS entries: entry
// \`id\` of slot \`s\` is words 0–3 of entity \`id\`'s instance record (position, rotation and
// type; world/src/entity/pack.rs) as of the frame that wrote slot \`s\`, or zero where the
// entity did not exist (no record is all zero: its rotation word would not be a unit
// quaternion). One pass per frame fills this frame's slot.

const ENTITY_IDS: u32 = NO_ENTITY;

fn pose_word(slot: u32, id: u32) -> u32 {
    return gi.off_queue_list + 64u * region_count() + 4u * (slot * ENTITY_IDS + id);
}

// Entity \`id\`'s record words 0–3 in TAA slot \`slot\` (zero: it did not exist).
fn pose_words(slot: u32, id: u32) -> vec4<u32> {
    let at = pose_word(slot, id);
    return vec4<u32>(words[at], words[at + 1u], words[at + 2u], words[at + 3u]);
}

// An entity's placement: its local origin (relative to this frame's integer camera
// position) and the rotation from world to entity axes.
struct Pose {
    origin: vec3<f32>,
    to_local: vec4<f32>,
}

fn pose_of(w: vec4<u32>) -> Pose {
    let pos = record_position(w.x, w.y);
    let origin = vec3<f32>(vec3<i32>(pos >> vec3<u32>(7u)) - frame.cam_int) + vec3<f32>(pos & vec3<u32>(127u)) / 128.0;
    return Pose(origin, decode_quat(w.z, w.w & 0xFFFu));
}

// Point \`p\` (relative to this frame's integer camera position) of an entity placed at
// \`was\`, where it lies when the entity is placed at \`now\`.
fn carry(p: vec3<f32>, was: Pose, now: Pose) -> vec3<f32> {
    return now.origin + rotate(conjugate(now.to_local), rotate(was.to_local, p - was.origin));
}

// ---- Pass gi_poses: one thread per entity id writes its entry of this frame's slot ----

@compute @workgroup_size(64)
fn gi_poses(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) li: u32) {
    let id = flat_id(wg, groups, li);
    if id >= ENTITY_IDS {
        return;
    }
    // The instance buffer holds entity \`id\`'s record in slot \`id\` (zero: no such entity;
    // past the world's slots, local instances, whose records carry no entity id).
    var record = vec4<u32>(0u);
    let e = select(0u, instance_word(id * RECORD_WORDS + 4u), id < world_info.instance_slots);
    if e != 0u && record_id(e) == id {
        let r = id * RECORD_WORDS;
        record = vec4<u32>(instance_word(r), instance_word(r + 1u), instance_word(r + 2u), instance_word(r + 3u));
    }
    let at = pose_word(gi.taa_slot, id);
    for (var k = 0u; k < 4u; k++) {
        words[at + k] = record[k];
    }
}

// The GI pipeline's per-pixel passes around the samples (docs/RENDERING.md §3c): the first
// hit, the long-term TAA's reprojection, and the TAA merge that stores this frame's sample.

// ---- The long-term TAA's 64-bit samples ----
//
// x: the chain length as f16 without its sign bit (15 bits) | the hash << 16.
// y: R, G, B in 8 bits each on a log scale (c = 12·log2(x/100 + 2^(−255/12)) + 255,
//    c = 0 is black, a step is 5.9 %) | normal id << 24 | cls << 27.

const TAA_LOG_FLOOR: f32 = 4.1529e-7; // 2^(−255/12)
const TAA_MAX: f32 = 100.0;
// How far (pixels) a history sample may land from this pixel's sample when reprojected back.
const TAA_RADIUS: f32 = 1.0;

fn taa_read(slot: u32, pixel: u32) -> vec2<u32> {
    let i = slot * pixel_count() + pixel;
    return taa_get(i);
}

fn taa_write(slot: u32, pixel: u32, v: vec2<u32>) {
    let i = slot * pixel_count() + pixel;
    taa_set(i, v);
}

// One channel on the log scale, rounded to the level below or above at random (\`u\`
// uniform in [0, 1)) with the odds that make the decoded value's mean exactly \`x\`: the
// TAA's mean is then unbiased in linear light (rounding by the fraction of the log-scale
// position is unbiased in the log domain only, and the decoding's convexity makes that
// brighter on average).
fn taa_channel(x: f32, u: f32) -> u32 {
    if x <= 0.0 {
        return 0u;
    }
    let c = clamp(12.0 * log2(x / TAA_MAX + TAA_LOG_FLOOR) + 255.0, 0.0, 255.0);
    let lo = u32(floor(c));
    if lo >= 255u {
        return 255u;
    }
    let below = taa_decode_channel(lo);
    let above = taa_decode_channel(lo + 1u);
    return select(lo, lo + 1u, u * (above - below) < x - below);
}

fn taa_decode_channel(c: u32) -> f32 {
    if c == 0u {
        return 0.0;
    }
    return max(TAA_MAX * (exp2((f32(c) - 255.0) / 12.0) - TAA_LOG_FLOOR), 0.0);
}

fn taa_colour(y: u32) -> vec3<f32> {
    return vec3<f32>(taa_decode_channel(y & 0xFFu), taa_decode_channel((y >> 8u) & 0xFFu), taa_decode_channel((y >> 16u) & 0xFFu));
}

fn taa_distance(x: u32) -> f32 {
    return unpack2x16float(x & 0x7FFFu).x;
}

// ---- Pass gi_first_hit ----

@compute @workgroup_size(8, 8)
fn gi_first_hit(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let r = ray_new(frame.cam_int, frame.cam_frac, camera_dir(frame, gid.xy, vec2<f32>(gi.jitter_x, gi.jitter_y)));
    let c = first_hit_chain(r, trace(r), false);
    let dn = c.r.d / c.r.len;
    var emit = vec3<f32>(0.0);
    var thr = c.throughput;
    var kind = KIND_DIFFUSE;
    var cls = CLASS_NONE;
    var nid = NO_NORMAL;
    var mat_id = 0u;
    var entity = NO_ENTITY;
    var p = vec3<f32>(0.0);
    // A ray that ran out of steps brings no light, as in the path tracer.
    if c.end == CHAIN_SKY && !c.h.exhausted {
        // Evaluated directly, not from the table: a camera ray's sky is seen as it is,
        // and the table's interpolation error would show across every sky pixel.
        emit = c.throughput * (sky_direct(dn) + sun_disc(dn));
    } else if c.end == CHAIN_SURFACE {
        let m = material(c.h.material);
        kind = m.kind;
        mat_id = c.h.material;
        entity = c.h.entity;
        nid = normal_id(c.n);
        p = vec3<f32>(c.r.o_int - frame.cam_int) + ray_local(c.r, c.h.t);
        if m.kind == KIND_EMISSIVE {
            emit = c.throughput * m.albedo * m.emission;
        }
        if m.kind == KIND_METAL {
            cls = CLASS_GLOSSY;
        } else {
            cls = CLASS_DIFFUSE;
            thr *= m.albedo;
        }
    }
    // The hash of what the pixel sees, for the TAA: its cls, its entity and the normals
    // of the mirrors on the way (docs/RENDERING.md §3c).
    var key = cls | (entity << 2u);
    for (var s = 0u; s < MAX_SEGMENTS - 1u; s++) {
        let next = c.planes[s + 1u];
        if next != HIT_UNDEFINED {
            key = pcg_hash(key ^ ((c.planes[s] & 7u) << (3u * s)));
        }
    }
    let hash = pcg_hash(key ^ nid) & 0xFFFFu;
    mem_set(gi.off_gbuf + i, bitcast<vec4<u32>>(vec4<f32>(p, c.distance)));
    let wo = oct_encode(-dn);
    mem_set(gi.off_gmat + i, vec4<u32>(
        kind | (cls << 4u) | (nid << 8u) | (mat_id << 16u),
        hash | (oct_encode(c.n) << 16u),
        pack2x16float(thr.rg),
        (pack2x16float(vec2<f32>(thr.b, 0.0)) & 0xFFFFu) | (wo << 16u),
    ));
    // The entity the pixel sees directly (not in a mirror), whose poses the TAA follows.
    var seen = NO_ENTITY;
    if c.end == CHAIN_SURFACE && c.planes[1] == HIT_UNDEFINED {
        seen = entity;
    }
    mem_set(gi.off_emitted + i, bitcast<vec4<u32>>(vec4<f32>(emit, f32(seen))));
}

// ---- Pass gi_taa: the long-term TAA's gather ----

fn chain_length(i: u32) -> f32 {
    let d = bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).w;
    return select(d, SKY_DIST, d < 0.0);
}

fn hash_at(i: u32) -> u32 {
    return mem_get(gi.off_gmat + i).y & 0xFFFFu;
}

@compute @workgroup_size(8, 8)
fn gi_taa(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let d = chain_length(i);
    var lo = d;
    var hi = d;
    var hashes = array<u32, 9>(0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u, 0u);
    var k = 0u;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let x = clamp(i32(gid.x) + dx, 0, i32(frame.width) - 1);
            let y = clamp(i32(gid.y) + dy, 0, i32(frame.height) - 1);
            let j = u32(x) + u32(y) * frame.width;
            lo = min(lo, chain_length(j));
            hi = max(hi, chain_length(j));
            hashes[k] = hash_at(j);
            k++;
        }
    }
    mem_set(gi.off_taa_info + 2u * i + 1u, bitcast<vec4<u32>>(vec4<f32>(lo, hi, 0.0, 0.0)));
    let sky = d >= SKY_DIST;
    // The point the pixel sees along its unjittered ray, relative to this frame's integer
    // camera position like the cameras (the sky: its direction).
    let dir = normalize(camera_dir(frame, gid.xy, vec2<f32>(0.5)));
    let here = cam(0u);
    var point = here.pos + dir * d;
    if sky {
        point = dir;
    }
    // An entity seen directly: its samples of earlier frames are found where its pose of
    // that frame put the point.
    let seen = u32(bitcast<vec4<f32>>(mem_get(gi.off_emitted + i)).w);
    let follow = seen != NO_ENTITY && !sky;
    var pose_now = Pose(vec3<f32>(0.0), vec4<f32>(0.0, 0.0, 0.0, 1.0));
    if follow {
        pose_now = pose_of(pose_words(gi.taa_slot, seen));
    }
    // How recently the pixel's surface changed, or light near it (none for the sky).
    var marks = vec2<u32>(0u);
    if !sky {
        marks = changes_at(bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).xyz, surface_normal(mem_get(gi.off_gmat + i)));
    }
    let edit = max(gi.edit_frame, marks.y);
    var sum = vec3<f32>(0.0);
    var count = 0.0;
    for (var age = 1u; age <= gi.taa_valid; age++) {
        let taken = gi.frame - age;
        // A sample from before the surface's own chunk changed shows what is gone (an
        // entity's own moves change its chunks: its history follows its poses instead).
        if taken < marks.x && !follow {
            break;
        }
        // Light from before a world change near the surface (or a change of the
        // materials) fades out within EDIT_HISTORY_FRAMES frames; so does light resampled
        // from the ring while it still held samples from before the change (the first
        // EDIT_HISTORY_FRAMES frames after it).
        if edit > 0u && taken < edit + EDIT_HISTORY_FRAMES && age > EDIT_HISTORY_FRAMES {
            break;
        }
        let c = cam(age);
        // Where the point was then: an entity's moves carry it.
        var then = point;
        var pose_then = pose_now;
        if follow {
            let w = pose_words((gi.taa_slot + TAA_SLOTS - age) % TAA_SLOTS, seen);
            // The entity did not exist then.
            if all(w == vec4<u32>(0u)) {
                break;
            }
            pose_then = pose_of(w);
            then = carry(point, pose_now, pose_then);
        }
        // From the same view, with nothing in the world changed since, the pixel's own
        // sample shows its footprint at that frame's jitter: it counts as it is. A pixel
        // that spans several voxels (a small model, a far wall) needs every one of its 32
        // jitters: the tests below would keep only those near the surface this frame's
        // jitter hit. A change anywhere ends this: a block removed in front of a far wall,
        // or an entity moved away from a floor, changes no chunk near the surface that
        // the pixel sees now, and yet its earlier samples show what was there.
        let still = same_view(c, here) && taken >= gi.change_frame;
        var qp = gid.xy;
        if !still {
            var v = then;
            if !sky {
                v = then - c.pos;
            }
            let pr = project(c, v);
            let q = pr.px - c.jitter + 0.5;
            if pr.z <= 0.0 || !on_image(q) {
                continue;
            }
            qp = vec2<u32>(q);
        }
        let s = taa_read((gi.taa_slot + TAA_SLOTS - age) % TAA_SLOTS, qp.x + qp.y * frame.width);
        if s.y == 0u && s.x == 0u {
            continue;
        }
        if still {
            sum += taa_colour(s.y);
            count += 1.0;
            continue;
        }
        let sd = taa_distance(s.x);
        let shash = s.x >> 16u;
        // A sample may show any of the 3×3 neighbours' surfaces (the pixel's footprint
        // straddles an edge across the jitters), except one from before a world change:
        // an entity that moved in (or a block placed) would take the old surface's
        // samples where its edge is, so those must show this pixel's own surface.
        var same = shash == hashes[4];
        if edit == 0u || taken >= edit {
            for (var h = 0u; h < 9u; h++) {
                same = same || shash == hashes[h];
            }
        }
        if !same {
            continue;
        }
        // Where the old sample's surface was (or, for the sky, its direction), seen from
        // this camera. On a silhouette the sky and the ground each keep their share: a
        // sample of either kind counts when the 3×3 neighbourhood still holds its kind
        // and it lands on this pixel.
        var back: Projection;
        let old_dir = normalize(cam_dir(c, qp));
        if sd >= SKY_DIST {
            if hi < SKY_DIST {
                continue;
            }
            back = project(here, old_dir);
        } else {
            var old = c.pos + old_dir * sd;
            if follow {
                old = carry(old, pose_then, pose_now);
            }
            let dist = length(old - here.pos);
            if dist < lo * (1022.0 / 1024.0) || dist > hi * (1026.0 / 1024.0) || sd > 2.0 * hi {
                continue;
            }
            back = project(here, old - here.pos);
        }
        let off = back.px - (vec2<f32>(gid.xy) + vec2<f32>(gi.jitter_x, gi.jitter_y));
        if back.z <= 0.0 || dot(off, off) > TAA_RADIUS * TAA_RADIUS {
            continue;
        }
        sum += taa_colour(s.y);
        count += 1.0;
    }
    mem_set(gi.off_taa_info + 2u * i, bitcast<vec4<u32>>(vec4<f32>(sum, count)));
}

// ---- Pass gi_merge: this frame's colour, its TAA sample and the result ----

@compute @workgroup_size(8, 8)
fn gi_merge(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let g = mem_get(gi.off_gmat + i);
    let thr = vec3<f32>(unpack2x16float(g.z), unpack2x16float(g.w).x);
    let colour = bitcast<vec4<f32>>(mem_get(gi.off_emitted + i)).rgb + thr * bitcast<vec4<f32>>(mem_get(gi.off_illum + i)).rgb;
    var rng = rng_new(frame.seed ^ 0x5A17u, i, gi.frame);
    var c = colour;
    let peak = max(c.r, max(c.g, c.b));
    if peak > TAA_MAX {
        c *= TAA_MAX / peak;
    }
    let y = taa_channel(c.r, rng_next(&rng)) | (taa_channel(c.g, rng_next(&rng)) << 8u)
        | (taa_channel(c.b, rng_next(&rng)) << 16u) | (((g.x >> 8u) & 7u) << 24u) | (((g.x >> 4u) & 3u) << 27u);
    let dist = chain_length(i);
    let x = (pack2x16float(vec2<f32>(dist, 0.0)) & 0x7FFFu) | ((g.y & 0xFFFFu) << 16u);
    taa_write(gi.taa_slot, i, vec2<u32>(x, y));
    let a = taa_accum(i);
    mem_set(gi.off_result + i, bitcast<vec4<u32>>(vec4<f32>((a.rgb + colour) / (a.w + 1.0), dist)));
}

// The GI pipeline's secondary samples (docs/RENDERING.md §3c): the ray queue, the secondary
// rays, and the region projection that gathers the samples of earlier frames into this
// frame's 8×8 regions, then refines each region to at most MAX_KEPT samples.
//
// A ring sample is RING_VEC4 = 3 vec4<u32>:
// 0: the primary surface point (relative to its frame's integer camera position), frame;
// 1: the sample point (same frame; for the sky: the direction), flags: sky | cls << 1 |
//    primary normal id << 4 | octahedral normal at the sample point << 16;
// 2: the radiance that came back along the secondary ray, the pdf it was drawn with.

var<workgroup> wg_flags: array<u32, 64>;
var<workgroup> wg_offsets: array<u32, 64>;
var<workgroup> wg_scan: array<u32, 256>;

const NO_PRIORITY: u32 = 0xFFFFFFFFu;

// Offsets in \`buckets\`.
fn bucket_priority(region: u32, slot: u32) -> u32 {
    return region * BUCKET_SLOTS + slot;
}

fn bucket_index(region: u32, slot: u32) -> u32 {
    return (region_count() + region) * BUCKET_SLOTS + slot;
}

// The lit and unlit counts of \`region\`, per normal id: lit at + 2·id, unlit at + 2·id + 1.
fn bucket_counts(region: u32) -> u32 {
    return 2u * region_count() * BUCKET_SLOTS + 2u * NORMALS * region;
}

// ---- Pass gi_queue: which pixels trace a secondary ray this frame ----
//
// One workgroup per region. A pixel with m − 1 accepted TAA samples (m ≤ QUEUE_PERIOD) is
// traced one frame in m, on a pattern that rotates every frame for every m:
// (frame + x + 2y) mod m. A traced pixel's path is also its own light that frame.
// The region's queued pixels are compacted in pixel order, so the queue is the same on
// every run. The pass also clears the region's buckets for the projection.
@compute @workgroup_size(8, 8)
fn gi_queue(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) li: u32,
    @builtin(workgroup_id) wid: vec3<u32>) {
    let region = wid.x + wid.y * gi.regions_x;
    if li < BUCKET_SLOTS {
        atomicStore(&buckets[bucket_priority(region, li)], NO_PRIORITY);
    }
    if li < 2u * NORMALS {
        atomicStore(&buckets[bucket_counts(region) + li], 0u);
    }
    var queued = 0u;
    let i = gid.x + gid.y * frame.width;
    // Only diffuse surfaces share samples; a metal traces its own (gi_resample.wgsl).
    if gid.x < frame.width && gid.y < frame.height && light.bounces > 0u && surface_class(mem_get(gi.off_gmat + i)) == CLASS_DIFFUSE {
        let m = u32(min(taa_accum(i).w, f32(QUEUE_PERIOD - 1u))) + 1u;
        if (gi.frame + gid.x + 2u * gid.y) % m == 0u {
            queued = 1u;
        }
    }
    wg_flags[li] = queued;
    workgroupBarrier();
    if li == 0u {
        var sum = 0u;
        for (var k = 0u; k < 64u; k++) {
            wg_offsets[k] = sum;
            sum += wg_flags[k];
        }
        words[CONTROL_WORDS + region] = sum;
    }
    workgroupBarrier();
    if queued == 1u {
        words[gi.off_queue_list + region * 64u + wg_offsets[li]] = i;
    }
}

// Indirect arguments for \`groups\` workgroups at \`at\`: 2D when over 65,535 (wgpu zeroes a
// larger 1D indirect dispatch).
fn write_args(at: u32, groups: u32) {
    words[at] = min(groups, 65535u);
    words[at + 1u] = max((groups + 65534u) / 65535u, 1u);
    words[at + 2u] = 1u;
}

// ---- Pass gi_queue_scan: one workgroup ----
//
// Prefix sums of the regions' queue counts (the queue's layout), this frame's place in the
// sample ring, how many ring samples the projection reads, and both indirect dispatches.
@compute @workgroup_size(256)
fn gi_queue_scan(@builtin(local_invocation_index) li: u32) {
    let regions = region_count();
    var carry = 0u;
    for (var base = 0u; base < regions; base += 256u) {
        let r = base + li;
        var v = 0u;
        if r < regions {
            v = words[CONTROL_WORDS + r];
        }
        wg_scan[li] = v;
        workgroupBarrier();
        for (var off = 1u; off < 256u; off <<= 1u) {
            var add = 0u;
            if li >= off {
                add = wg_scan[li - off];
            }
            workgroupBarrier();
            wg_scan[li] += add;
            workgroupBarrier();
        }
        if r < regions {
            words[CONTROL_WORDS + regions + r] = carry + wg_scan[li] - v;
        }
        carry += wg_scan[255];
        workgroupBarrier();
    }
    if li != 0u {
        return;
    }
    let cap = gi.ring_capacity;
    let total = carry;
    let stored = min(total, cap);
    let start = words[CONTROL_HEAD];
    words[CONTROL_QUEUED] = total;
    words[CONTROL_START] = start;
    words[CONTROL_HEAD] = (start + stored) % cap;
    words[CONTROL_FRAMES + gi.frame % CAMERA_HISTORY] = stored;
    // The newest frames whose samples all fit in the ring (and are still valid).
    var valid = 0u;
    for (var age = 0u; age <= cams_valid(); age++) {
        if gi.frame - age < gi.edit_frame && age > EDIT_HISTORY_FRAMES {
            break;
        }
        let n = words[CONTROL_FRAMES + (gi.frame - age) % CAMERA_HISTORY];
        if valid + n > cap {
            break;
        }
        valid += n;
    }
    words[CONTROL_VALID] = valid;
    write_args(CONTROL_TRACE_ARGS, (stored + 63u) / 64u);
    write_args(CONTROL_PROJECT_ARGS, (valid + 63u) / 64u);
}

// ---- Pass gi_trace: one secondary path per queued pixel ----
@compute @workgroup_size(64)
fn gi_trace(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) li: u32) {
    let t = flat_id(wid, groups, li);
    if t >= min(words[CONTROL_QUEUED], gi.ring_capacity) {
        return;
    }
    // The region holding queue entry t: the last one starting at or before it.
    let regions = region_count();
    var lo = 0u;
    var hi = regions - 1u;
    while lo < hi {
        let mid = (lo + hi + 1u) / 2u;
        if words[CONTROL_WORDS + regions + mid] <= t {
            lo = mid;
        } else {
            hi = mid - 1u;
        }
    }
    let pixel = words[gi.off_queue_list + lo * 64u + t - words[CONTROL_WORDS + regions + lo]];
    // Seeded by the pixel and the frame, never by the queue slot.
    var rng = rng_new(frame.seed, pixel, gi.frame);
    let g = mem_get(gi.off_gmat + pixel);
    let p = bitcast<vec4<f32>>(mem_get(gi.off_gbuf + pixel)).xyz;
    let n = surface_normal(g);
    let cls = surface_class(g);
    let origin = p + n * SURFACE_OFFSET;
    let dir = sample_cosine(n, vec2<f32>(rng_next(&rng), rng_next(&rng)));
    let pdf = max(dot(n, dir), 0.0) / PI;
    var s = PathSample(vec3<f32>(0.0), -1.0, n);
    if pdf > 0.0 {
        let base = ray_new(frame.cam_int, vec3<f32>(0.0), dir);
        s = path_radiance(ray_at(base, origin, dir), light.bounces - 1u, false, &rng);
    }
    let sky = s.distance < 0.0;
    var point = dir;
    var ns = n;
    if !sky {
        point = origin + dir * s.distance;
        ns = s.normal;
    }
    let idx = (words[CONTROL_START] + t) % gi.ring_capacity;
    mem_set(gi.off_ring + RING_VEC4 * idx, vec4<u32>(bitcast<vec3<u32>>(p), gi.frame));
    mem_set(gi.off_ring + RING_VEC4 * idx + 1u, vec4<u32>(bitcast<vec3<u32>>(point),
        select(0u, 1u, sky) | (cls << 1u) | (surface_normal_id(g) << 4u) | (oct_encode(ns) << 16u)));
    let radiance = bitcast<vec3<u32>>(max(s.radiance, vec3<f32>(0.0)));
    mem_set(gi.off_ring + RING_VEC4 * idx + 2u, vec4<u32>(radiance, bitcast<u32>(pdf)));
    // The pixel's own estimate of its incoming light this frame (cosine-weighted, so the
    // radiance itself), tagged with the frame + 1 (the array starts zeroed).
    mem_set(gi.off_own + pixel, vec4<u32>(radiance, gi.frame + 1u));
}

// ---- Passes gi_project and gi_project_store: the ring's samples into this frame's regions ----

struct Projected {
    ok: bool,
    region: u32,
    // The primary surface's normal id.
    nid: u32,
    lit: bool,
    priority: u32,
    idx: u32,
}

// Ring sample number \`t\` counting back from the newest, projected into this frame: its
// primary surface must land on a pixel of the same cls and normal, on the same plane.
fn project_sample(t: u32) -> Projected {
    let none = Projected(false, 0u, 0u, false, NO_PRIORITY, 0u);
    if t >= words[CONTROL_VALID] {
        return none;
    }
    let cap = gi.ring_capacity;
    let newest = (words[CONTROL_START] + min(words[CONTROL_QUEUED], cap) + cap - 1u) % cap;
    let idx = (newest + cap - t) % cap;
    let e0 = mem_get(gi.off_ring + RING_VEC4 * idx);
    let e1 = mem_get(gi.off_ring + RING_VEC4 * idx + 1u);
    let age = gi.frame - e0.w;
    if age > cams_valid() {
        return none;
    }
    let here = cam(0u);
    let p = bitcast<vec4<f32>>(e0).xyz + cam(age).origin;
    // Light traced before a change of the sample's surface, or of the surface its path
    // hit (a removed or added emitter), is dropped; light traced before a change near
    // either lasts EDIT_HISTORY_FRAMES frames, as after a change of the materials.
    var marks = changes_at(p, normal_of_id((e1.w >> 4u) & 7u));
    if (e1.w & 1u) == 0u {
        marks = max(marks, changes_at(bitcast<vec4<f32>>(e1).xyz + cam(age).origin, oct_decode(e1.w >> 16u)));
    }
    let edit = max(gi.edit_frame, marks.y);
    if e0.w < marks.x || (e0.w < edit && age > EDIT_HISTORY_FRAMES) {
        return none;
    }
    let pr = project(here, p - here.pos);
    if !on_image(pr.px) || pr.z <= 0.0 {
        return none;
    }
    let q = vec2<u32>(pr.px);
    let qi = q.x + q.y * frame.width;
    let g = mem_get(gi.off_gmat + qi);
    if surface_class(g) != ((e1.w >> 1u) & 3u) || surface_normal_id(g) != ((e1.w >> 4u) & 7u) {
        return none;
    }
    let off = abs(dot(surface_normal(g), p - bitcast<vec4<f32>>(mem_get(gi.off_gbuf + qi)).xyz));
    if off > 0.05 + 0.002 * length(p - here.pos) {
        return none;
    }
    let rgb = bitcast<vec4<f32>>(mem_get(gi.off_ring + RING_VEC4 * idx + 2u)).xyz;
    // Drawn anew each frame, so that a region's winners (and the light its pixels
    // resample) change from frame to frame and the TAA averages independent draws.
    let priority = min(pcg_hash(pcg_hash(pcg_hash(e0.w) ^ idx) ^ gi.frame), NO_PRIORITY - 1u);
    return Projected(true, region_of(q.x, q.y), (e1.w >> 4u) & 7u, any(rgb > vec3<f32>(0.0)), priority, idx);
}

// Counts lit and unlit samples per region; each lit sample bids for one of its region's
// BUCKET_SLOTS slots with a priority hashed from its frame, its ring index and this frame,
// so that the winners are a random subset that does not depend on the order threads run in.
@compute @workgroup_size(64)
fn gi_project(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) li: u32) {
    let s = project_sample(flat_id(wid, groups, li));
    if !s.ok {
        return;
    }
    if s.lit {
        atomicAdd(&buckets[bucket_counts(s.region) + 2u * s.nid], 1u);
        atomicMin(&buckets[bucket_priority(s.region, pcg_hash(s.priority) % BUCKET_SLOTS)], s.priority);
    } else {
        atomicAdd(&buckets[bucket_counts(s.region) + 2u * s.nid + 1u], 1u);
    }
}

// The winners write their ring index into their slot.
@compute @workgroup_size(64)
fn gi_project_store(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) li: u32) {
    let s = project_sample(flat_id(wid, groups, li));
    if !s.ok || !s.lit {
        return;
    }
    let slot = pcg_hash(s.priority) % BUCKET_SLOTS;
    if atomicLoad(&buckets[bucket_priority(s.region, slot)]) == s.priority {
        atomicStore(&buckets[bucket_index(s.region, slot)], s.idx);
    }
}

// ---- Pass gi_refine: at most MAX_KEPT samples per region ----
//
// Brightness levelling: a sample whose brightest channel is m, in a region whose brightest
// is M, is kept with probability m/M and then scaled by M/m (unbiased); a removed sample
// counts as unlit. The region's lit ratio is kept / (slots filled + the unlit count scaled
// like the lit one).
@compute @workgroup_size(64)
fn gi_refine(@builtin(global_invocation_id) gid: vec3<u32>) {
    let region = gid.x;
    if region >= region_count() {
        return;
    }
    // What the region's pixels see: their normals and chain lengths.
    var mask = 0u;
    var lo = SKY_DIST;
    var hi = 0.0;
    let x0 = (region % gi.regions_x) * 8u;
    let y0 = (region / gi.regions_x) * 8u;
    for (var k = 0u; k < 64u; k++) {
        let x = x0 + k % 8u;
        let y = y0 + k / 8u;
        if x < frame.width && y < frame.height {
            let i = x + y * frame.width;
            let g = mem_get(gi.off_gmat + i);
            if surface_class(g) != CLASS_NONE {
                mask |= 1u << surface_normal_id(g);
                lo = min(lo, bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).w);
                hi = max(hi, bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).w);
            }
        }
    }
    // Per normal id: slots filled and samples that survive levelling.
    var filled = array<u32, 6>(0u, 0u, 0u, 0u, 0u, 0u);
    var survivors = array<u32, 6>(0u, 0u, 0u, 0u, 0u, 0u);
    var peak = 0.0;
    for (var s = 0u; s < BUCKET_SLOTS; s++) {
        if atomicLoad(&buckets[bucket_priority(region, s)]) != NO_PRIORITY {
            let idx = atomicLoad(&buckets[bucket_index(region, s)]);
            filled[min((mem_get(gi.off_ring + RING_VEC4 * idx + 1u).w >> 4u) & 7u, NORMALS - 1u)]++;
            let rgb = bitcast<vec4<f32>>(mem_get(gi.off_ring + RING_VEC4 * idx + 2u)).xyz;
            peak = max(peak, max(rgb.r, max(rgb.g, rgb.b)));
        }
    }
    var rng = rng_new(frame.seed ^ 0x7E71u, region, gi.frame);
    var kept = 0u;
    for (var s = 0u; s < BUCKET_SLOTS; s++) {
        if atomicLoad(&buckets[bucket_priority(region, s)]) == NO_PRIORITY {
            continue;
        }
        let idx = atomicLoad(&buckets[bucket_index(region, s)]);
        let e0 = mem_get(gi.off_ring + RING_VEC4 * idx);
        let e1 = mem_get(gi.off_ring + RING_VEC4 * idx + 1u);
        let e2 = mem_get(gi.off_ring + RING_VEC4 * idx + 2u);
        let rgb = bitcast<vec4<f32>>(e2).xyz;
        let m = max(rgb.r, max(rgb.g, rgb.b));
        if rng_next(&rng) * peak >= m {
            continue;
        }
        survivors[min((e1.w >> 4u) & 7u, NORMALS - 1u)]++;
        if kept == MAX_KEPT {
            continue;
        }
        let col = min(rgb * (peak / m), vec3<f32>(65000.0));
        let shift = cam(gi.frame - e0.w).origin;
        let sky = (e1.w & 1u) != 0u;
        var point = bitcast<vec4<f32>>(e1).xyz;
        var jac = 1.0;
        if !sky {
            point += shift;
            let primary = bitcast<vec4<f32>>(e0).xyz + shift;
            let v = point - primary;
            let d2 = max(dot(v, v), 1e-8);
            jac = abs(dot(oct_decode(e1.w >> 16u), v * inverseSqrt(d2))) / d2;
        }
        let at = 2u * (region * MAX_KEPT + kept);
        mem_set(gi.off_refined + at, vec4<u32>(bitcast<vec3<u32>>(point), e1.w & 0xFFFF007Fu));
        mem_set(gi.off_refined + at + 1u, vec4<u32>(pack2x16float(col.rg), pack2x16float(vec2<f32>(col.b, 0.0)), e2.w, bitcast<u32>(jac)));
        kept++;
    }
    // The lit ratio per normal: the light a surface facing one way gets says nothing of
    // another's in the same region.
    var ratio = array<f32, 6>(0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    var total = 0u;
    for (var n = 0u; n < NORMALS; n++) {
        let lit = atomicLoad(&buckets[bucket_counts(region) + 2u * n]);
        let unlit = atomicLoad(&buckets[bucket_counts(region) + 2u * n + 1u]);
        total += lit + unlit;
        let unlit_scaled = f32(unlit) * f32(filled[n]) / max(f32(lit), 1.0);
        ratio[n] = f32(survivors[n]) / max(f32(filled[n]) + unlit_scaled, 1.0);
    }
    let base = gi.off_region_info + 3u * region;
    mem_set(base, bitcast<vec4<u32>>(vec4<f32>(ratio[0], ratio[1], ratio[2], ratio[3])));
    mem_set(base + 1u, bitcast<vec4<u32>>(vec4<f32>(ratio[4], ratio[5], f32(kept), f32(total))));
    mem_set(base + 2u, bitcast<vec4<u32>>(vec4<f32>(f32(mask), lo, hi, 0.0)));
}

// The GI pipeline's per-pixel shading (docs/RENDERING.md §3c): spatial resampling of the
// regions' refined samples with one visibility ray, the sun by next-event estimation, and
// the separable sparse bilateral denoiser.

// Candidates per pixel: half in the small window, half in the large one.
const CANDIDATES: u32 = 12u;
// The large window's side as a fraction of the image height; the small one's as a
// fraction of the large one's.
const WINDOW: f32 = 0.35;
const SMALL_WINDOW: f32 = 0.1;
// The denoiser: taps each side at DENOISE_HEIGHT rows (the paper's 1440p; fewer in
// proportion on smaller images, so that it covers the same share of the picture), the
// Gaussian's σ as a share of its reach, the guide's strength, and how much of the
// filtered value it keeps. The taps are 2 px apart.
const DENOISE_TAPS: f32 = 10.0;
const DENOISE_HEIGHT: f32 = 1440.0;
const DENOISE_SIGMA: f32 = 1.0;
const DENOISE_GUIDE: f32 = 8.0;
const DENOISE_BLEND: f32 = 0.92;
// How much nearer than a surface sample (in voxels, before the 4 % margin) the visibility
// ray may stop and still see it: a ray toward a voxel face at a grazing angle often clips
// the neighbouring voxel's edge first.
const VISIBLE_SLACK: f32 = 1.0;

// A coordinate mirrored back into [0, size).
fn mirrored(v: i32, size: i32) -> u32 {
    var x = v;
    if x < 0 {
        x = -x;
    }
    if x >= size {
        x = 2 * size - 2 - x;
    }
    return u32(clamp(x, 0, size - 1));
}

struct Candidate {
    // The integrand (radiance × BRDF × cos) toward the sample, its direction and distance.
    f: vec3<f32>,
    dir: vec3<f32>,
    distance: f32,
    sky: bool,
    goal: f32,
}

// The light a diffuse surface at \`p\` (normal \`n\`, id \`nid\`) of pixel \`gid\` reflects (before
// its albedo), by resampling the regions' refined samples; w is 0 when no candidate could
// speak for this surface (no estimate, which is not the same as darkness).
fn resampled(gid: vec2<u32>, p: vec3<f32>, n: vec3<f32>, nid: u32, dist_here: f32, rng: ptr<function, u32>) -> vec4<f32> {
    let origin = p + n * (2.0 * SURFACE_OFFSET);
    let base = ray_new(frame.cam_int, vec3<f32>(0.0), n);
    let big = WINDOW * f32(frame.height);
    var wsum = 0.0;
    var count = 0u;
    var chosen = Candidate(vec3<f32>(0.0), n, 0.0, true, 0.0);
    for (var c = 0u; c < CANDIDATES; c++) {
        let side = select(big, big * SMALL_WINDOW, c < CANDIDATES / 2u);
        let off = (vec2<f32>(rng_next(rng), rng_next(rng)) - 0.5) * side;
        let qx = mirrored(i32(gid.x) + i32(round(off.x)), i32(frame.width));
        let qy = mirrored(i32(gid.y) + i32(round(off.y)), i32(frame.height));
        let region = region_of(qx, qy);
        let ratios = bitcast<vec4<f32>>(mem_get(gi.off_region_info + 3u * region));
        let info = bitcast<vec4<f32>>(mem_get(gi.off_region_info + 3u * region + 1u));
        let shape = bitcast<vec4<f32>>(mem_get(gi.off_region_info + 3u * region + 2u));
        let pick = rng_next(rng);
        // A region with no samples says nothing; one whose surfaces differ from this one
        // does not speak for it.
        if info.w == 0.0 || (u32(shape.x) & (1u << nid)) == 0u || dist_here < 0.5 * shape.y || dist_here > 2.0 * shape.z {
            continue;
        }
        let kept = u32(info.z);
        if kept == 0u {
            // Every sample of the region was unlit: a zero that counts.
            count++;
            continue;
        }
        // One of the region's kept samples drawn by a surface facing this way (the others
        // were drawn from other distributions and do not speak for this surface).
        var matching = 0u;
        for (var k = 0u; k < kept; k++) {
            matching += select(0u, 1u, ((mem_get(gi.off_refined + 2u * (region * MAX_KEPT + k)).w >> 4u) & 7u) == nid);
        }
        if matching == 0u {
            continue;
        }
        var want = min(u32(pick * f32(matching)), matching - 1u);
        var at = 0u;
        for (var k = 0u; k < kept; k++) {
            let here_at = 2u * (region * MAX_KEPT + k);
            if ((mem_get(gi.off_refined + here_at).w >> 4u) & 7u) == nid {
                if want == 0u {
                    at = here_at;
                    break;
                }
                want--;
            }
        }
        let r0 = mem_get(gi.off_refined + at);
        let r1 = mem_get(gi.off_refined + at + 1u);
        let sky = (r0.w & 1u) != 0u;
        var dir = bitcast<vec4<f32>>(r0).xyz;
        var distance = 0.0;
        var jac = 1.0;
        if !sky {
            let v = dir - origin;
            distance = length(v);
            dir = v / max(distance, 1e-6);
            jac = abs(dot(oct_decode(r0.w >> 16u), dir)) / max(distance * distance, 1e-8) / max(bitcast<f32>(r1.w), 1e-12);
            if jac < 0.3 || jac > 2.5 {
                continue;
            }
        }
        let cos_now = dot(n, dir);
        let pdf_then = bitcast<f32>(r1.z);
        if cos_now <= 1e-4 || pdf_then < 0.01 {
            continue;
        }
        let f = cos_now / PI;
        let ratio = f / pdf_then;
        if ratio < 0.25 || ratio > 2.0 {
            continue;
        }
        var lit_ratio = info.x;
        if nid < 4u {
            lit_ratio = ratios[nid];
        } else if nid == 5u {
            lit_ratio = info.y;
        }
        let colour = vec3<f32>(unpack2x16float(r1.x), unpack2x16float(r1.y).x) * lit_ratio;
        let fc = colour * f;
        let goal = luminance(fc);
        if goal <= 0.0 {
            continue;
        }
        count++;
        let w = goal / pdf_then * jac;
        wsum += w;
        if rng_next(rng) * wsum < w {
            chosen = Candidate(fc, dir, distance, sky, goal);
        }
    }
    if wsum > 0.0 {
        // One visibility ray toward the chosen sample.
        let h = trace(ray_at(base, origin, chosen.dir));
        var visible = !h.hit && !h.exhausted;
        if !chosen.sky {
            visible = h.hit && (h.t * length(chosen.dir) + VISIBLE_SLACK) * 1.04 >= chosen.distance;
        }
        if visible {
            return vec4<f32>(chosen.f * (wsum / (f32(count) * chosen.goal)), 1.0);
        }
    }
    return vec4<f32>(0.0, 0.0, 0.0, select(0.0, 1.0, count > 0u));
}

// ---- Pass gi_resample ----
@compute @workgroup_size(8, 8)
fn gi_resample(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let g = mem_get(gi.off_gmat + i);
    let cls = surface_class(g);
    let a = taa_accum(i);
    let thr = vec3<f32>(unpack2x16float(g.z), unpack2x16float(g.w).x);
    if cls == CLASS_NONE || light.bounces == 0u {
        mem_set(gi.off_illum + i, bitcast<vec4<u32>>(vec4<f32>(0.0)));
        return;
    }
    let p = bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).xyz;
    let dist_here = bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).w;
    let n = surface_normal(g);
    let nid = surface_normal_id(g);
    let m = material(g.x >> 16u);
    let alpha = max(m.roughness, MIN_ALPHA);
    let wo = oct_decode(g.w >> 16u);
    let base = ray_new(frame.cam_int, vec3<f32>(0.0), n);
    var rng = rng_new(frame.seed ^ 0x2E5Au, i, gi.frame);
    var light_in = vec3<f32>(0.0);
    // A metal traces its own path every frame: its lobe depends on the view, so its
    // neighbours' samples rarely serve it. So does a diffuse surface that no candidate
    // could speak for (rather than count as dark).
    var own = cls == CLASS_GLOSSY;
    if !own {
        let mine = mem_get(gi.off_own + i);
        if mine.w == gi.frame + 1u {
            // The pixel traced its own secondary path this frame (gi_queue): an unbiased
            // estimate of its own light.
            light_in = bitcast<vec3<f32>>(mine.xyz);
        } else {
            let r = resampled(gid.xy, p, n, nid, dist_here, &rng);
            light_in = r.rgb;
            own = r.w == 0.0;
        }
    }
    if own {
        let u = vec2<f32>(rng_next(&rng), rng_next(&rng));
        var s = Scattered(sample_cosine(n, u), vec3<f32>(1.0));
        if cls == CLASS_GLOSSY {
            s = ggx_sample(n, wo, alpha, m.albedo, u);
        }
        if dot(s.dir, n) > 0.0 {
            let r = ray_at(base, p + n * SURFACE_OFFSET, s.dir);
            light_in = s.weight * path_radiance(r, light.bounces - 1u, false, &rng).radiance;
        }
    }
    // The sun, by next-event estimation over its disc.
    if light.sun_on != 0u {
        let u = vec2<f32>(rng_next(&rng), rng_next(&rng));
        let wi = sample_cone(light.sun_dir, light.sun_omc, u);
        let c = dot(n, wi);
        if c > 0.0 && !blocked(base, p + n * SURFACE_OFFSET, wi) {
            var f = vec3<f32>(1.0 / PI);
            if cls == CLASS_GLOSSY {
                f = ggx(n, wo, wi, alpha, m.albedo);
            }
            light_in += f * (c * light.sun_weight);
        }
    }
    // The denoiser's guide: the TAA's brightness without the surface's colour.
    var guide = luminance(light_in);
    if a.w > 1.0 {
        guide = luminance(a.rgb / a.w) / (luminance(thr) + 0.01);
    }
    mem_set(gi.off_illum + i, bitcast<vec4<u32>>(vec4<f32>(light_in, guide)));
}

// ---- Passes gi_denoise_x and gi_denoise_y ----

// The weight of tap \`j\` for pixel \`i\`: the same plane and cls, a close guide value, and
// a Gaussian in \`k\`, the tap's place in the filter's reach (−1 to 1).
fn denoise_weight(i: u32, j: u32, k: f32, gi_: f32, gj: f32) -> f32 {
    let a = mem_get(gi.off_gmat + i);
    let b = mem_get(gi.off_gmat + j);
    if surface_class(a) != surface_class(b) || surface_normal_id(a) != surface_normal_id(b) {
        return 0.0;
    }
    if abs(dot(surface_normal(a), bitcast<vec4<f32>>(mem_get(gi.off_gbuf + j)).xyz - bitcast<vec4<f32>>(mem_get(gi.off_gbuf + i)).xyz)) > 0.05 {
        return 0.0;
    }
    let kk = k / DENOISE_SIGMA;
    return exp(-0.5 * kk * kk) / (1.0 + DENOISE_GUIDE * abs(gj - gi_) / (gi_ + gj + 0.01));
}

// The tap at \`k\` along \`axis\` from \`gid\`, shifted sideways by one pixel half the time.
fn denoise_tap(gid: vec2<u32>, k: i32, axis: u32, rng: ptr<function, u32>) -> u32 {
    var q = vec2<i32>(gid);
    var side = 0;
    if k != 0 && rng_next(rng) < 0.5 {
        side = select(-1, 1, rng_next(rng) < 0.5);
    }
    q[axis] += 2 * k;
    q[1u - axis] += side;
    let x = clamp(q.x, 0, i32(frame.width) - 1);
    let y = clamp(q.y, 0, i32(frame.height) - 1);
    return u32(x) + u32(y) * frame.width;
}

// One denoiser pass along \`axis\` (0: x, 1: y) from the \`mem\` array at \`src\` to the one at
// \`dst\`: each pixel blended toward the weighted mean of its taps, with the mean guide
// value; \`salt\` picks the pass's random stream.
fn denoise_pass(gid: vec3<u32>, axis: u32, src: u32, dst: u32, salt: u32) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let i = gid.x + gid.y * frame.width;
    let here = bitcast<vec4<f32>>(mem_get(src + i));
    var rng = rng_new(frame.seed ^ salt, i, gi.frame);
    var sum = vec4<f32>(0.0);
    var wsum = 0.0;
    let taps = i32(round(min(DENOISE_TAPS * f32(frame.height) / DENOISE_HEIGHT, DENOISE_TAPS)));
    // Only diffuse light is denoised: a metal's own path is view-dependent, and spreading
    // its sun glints would brighten its whole surface.
    if surface_class(mem_get(gi.off_gmat + i)) == CLASS_DIFFUSE && taps > 0 {
        for (var k = -taps; k <= taps; k++) {
            let j = denoise_tap(gid.xy, k, axis, &rng);
            let v = bitcast<vec4<f32>>(mem_get(src + j));
            let w = denoise_weight(i, j, f32(k) / f32(taps), here.w, v.w);
            sum += v * w;
            wsum += w;
        }
    }
    var out = here;
    if wsum > 0.0 {
        out = vec4<f32>(mix(here.rgb, sum.rgb / wsum, DENOISE_BLEND), sum.w / wsum);
    }
    mem_set(dst + i, bitcast<vec4<u32>>(out));
}

@compute @workgroup_size(8, 8)
fn gi_denoise_x(@builtin(global_invocation_id) gid: vec3<u32>) {
    denoise_pass(gid, 0u, gi.off_illum, gi.off_illum2, 0xD0E1u);
}

@compute @workgroup_size(8, 8)
fn gi_denoise_y(@builtin(global_invocation_id) gid: vec3<u32>) {
    denoise_pass(gid, 1u, gi.off_illum2, gi.off_illum, 0xD0E2u);
}

const TAA_SLOTS: u32 = 32u;
const CONTROL_WORDS: u32 = 144u;
const CAMERA_HISTORY: u32 = 128u;
const LUT_SIZE: u32 = 256u;
const BUCKET_SLOTS: u32 = 32u;
const MAX_KEPT: u32 = 7u;
const QUEUE_PERIOD: u32 = 2u;
const RING_VEC4: u32 = 3u;
const EDIT_HISTORY_FRAMES: u32 = 8u;
const CONTROL_TRACE_ARGS: u32 = 0u;
const CONTROL_PROJECT_ARGS: u32 = 4u;
const CAM_WORDS: u32 = 5u;
const CONTROL_QUEUED: u32 = 8u;
const CONTROL_START: u32 = 9u;
const CONTROL_VALID: u32 = 10u;
const CONTROL_HEAD: u32 = 11u;
const CONTROL_FRAMES: u32 = 16u;
// Generated by naadf-client (gi/memory.rs): the GI history's split arrays.
@group(1) @binding(6) var<storage, read_write> mem_0: array<vec4<u32>>;
fn mem_get(i: u32) -> vec4<u32> { return mem_0[i]; }
fn mem_set(i: u32, v: vec4<u32>) { mem_0[i] = v; }
@group(1) @binding(7) var<storage, read_write> taa_0: array<vec2<u32>>;
fn taa_get(i: u32) -> vec2<u32> { return taa_0[i]; }
fn taa_set(i: u32, v: vec2<u32>) { taa_0[i] = v; }
`,nl=e=>Math.min(1,Math.max(0,e*(2.51*e+.03)/(e*(2.43*e+.59)+.14))),rl=e=>Math.min(255,Math.max(0,Math.floor((e<=.0031308?12.92*e:1.055*e**(1/2.4)-.055)*255+.5)));function il(e,t,n,r,i){let a=new Uint8ClampedArray(t*n*4);for(let o=0;o<t*n;o++){let t=i&&e[4*o+3]||1;for(let n=0;n<3;n++)a[4*o+n]=rl(nl(Math.max(0,e[4*o+n]/t)*r));a[4*o+3]=255}return new ImageData(a,t,n)}function al(e,t){let n=e*t,r=Math.ceil(e/8)*Math.ceil(t/8),i=K.CAMERA_HISTORY*K.CAM_WORDS,a=e=>{let t=i;return i+=e,t},[o,s,c,l]=[a(K.LUT_SIZE*K.LUT_SIZE),a(n),a(n),a(n)],[u,d,f,p]=[a(2*n),a(n),a(n),a(n)],[m,h,g]=[a(r*K.MAX_KEPT*2),a(3*r),a(n)],_=K.CONTROL_WORDS+2*r,v={lut:o,gbuf:s,gmat:c,emitted:l,taaInfo:u,illum:d,illum2:f,result:p,refined:m,regionInfo:h,own:g,ringStart:i,queueList:_,words:_+64*r+K.POSE_TABLE_WORDS},y=n*K.RING_PER_PIXEL;return{width:e,height:t,pixels:n,regions:r,layout:v,ring:y,memBytes:(v.ringStart+y*K.RING_VEC4)*16,taaBytes:n*K.TAA_PIXEL_BYTES}}function ol(e,t,n){let r=Math.min(e.limits.maxStorageBufferBindingSize,e.limits.maxBufferSize),[i,a]=[t,n];for(;;){let e=al(i,a);if(Math.max(e.memBytes,e.taaBytes,e.layout.words*4)<=r||i===1&&a===1)return[i,a];[i,a]=[Math.ceil(i/2),Math.ceil(a/2)]}}function sl(e){let t=e%K.TAA_SLOTS,n=0;for(let e=0;e<32;e++)t&1<<e&&(n|=1<<31-e);let[r,i,a]=[0,0x80000000,t];for(;a>0;)a&1&&(r=(r^i)>>>0),a>>>=1,i=(i^i>>>1)>>>0;let o=Math.fround(.5/K.TAA_SLOTS),s=e=>Math.fround(Math.fround(((e^0x80000000)>>>0)/4294967296)+o);return[s(n>>>0),s(r)]}var cl=class{device;plan;chunks;frames=0;cameras=[];marks;generation;editFrame=0;changeFrame=0;words;changes;args;mem;staging;owned;group;constructor(e,t,n,r,i,a){this.device=e,this.plan=r,this.chunks=i;let o=(t,n,r)=>e.createBuffer({label:t,size:Math.max(16,n),usage:r}),s=GPUBufferUsage.STORAGE;this.words=o(`gi words`,r.layout.words*4,s|GPUBufferUsage.COPY_SRC);let c=o(`gi buckets`,r.regions*(2*K.BUCKET_SLOTS+12)*4,s),l=i[0]*i[1]*i[2];this.changes=o(`gi chunk changes`,l*8,s|GPUBufferUsage.COPY_DST),this.mem=o(`gi mem`,r.memBytes,s|GPUBufferUsage.COPY_DST|GPUBufferUsage.COPY_SRC);let u=o(`gi taa`,r.taaBytes,s);this.args=o(`gi indirect args`,K.ARGS_BYTES,GPUBufferUsage.INDIRECT|GPUBufferUsage.COPY_DST),this.staging=o(`gi result`,r.pixels*16,GPUBufferUsage.MAP_READ|GPUBufferUsage.COPY_DST),this.owned=[this.words,c,this.changes,this.mem,u,this.args,this.staging],this.marks=new Uint32Array(l*2),this.generation=a.generation,this.group=e.createBindGroup({layout:t,entries:[...n,this.words,c,this.changes,this.mem,u].map((e,t)=>({binding:t,resource:{buffer:e}}))})}destroy(){this.owned.forEach(e=>e.destroy())}noteChanges(e){if(this.generation===e.generation)return;let t=e.changesSince(this.generation);t===`everything`||t.length>K.MAX_LOCAL_CHANGES?[this.editFrame,this.changeFrame]=[this.frames,this.frames]:t.length>0&&(this.mark(t),this.changeFrame=this.frames),this.generation=e.generation}mark(e){let[t,n,r]=this.chunks,i=K.CHANGE_REACH,[a,o]=[1/0,0],s=(e,t)=>{this.marks[2*e+t]=this.frames,[a,o]=[Math.min(a,e),Math.max(o,e+1)]};for(let a of e){let[e,o,c]=[a%t,Math.floor(a/t)%n,Math.floor(a/(t*n))];s(a,0);for(let a=Math.max(0,c-i);a<=Math.min(r-1,c+i);a++)for(let r=Math.max(0,o-i);r<=Math.min(n-1,o+i);r++)for(let o=Math.max(0,e-i);o<=Math.min(t-1,e+i);o++)s(o+t*(r+n*a),1)}a<o&&this.device.queue.writeBuffer(this.changes,a*8,this.marks,a*2,(o-a)*2)}uploadCameras(e,t){let n=sl(this.frames);this.cameras.unshift({camera:e,jitter:n}),this.cameras.length=Math.min(this.cameras.length,K.CAMERA_HISTORY);let r=K.CAM_WORDS*4,i=new Float32Array(K.CAMERA_HISTORY*r);return this.cameras.forEach((e,n)=>{let a=Io({...e.camera,pos:e.camera.pos.map((e,n)=>e-t[n])},this.plan.width,this.plan.height),o=a.int.map((e,t)=>Math.fround(Math.fround(e)+a.frac[t]));i.set([...o,e.jitter[0],...a.forward,e.jitter[1],...a.right,0,...a.up,0,...a.int,0],n*r)}),this.device.queue.writeBuffer(this.mem,0,i),n}info(e){let{plan:t,frames:n}=this,r=t.layout;return gc(rc,{frame:n,taa_slot:n%K.TAA_SLOTS,taa_valid:Math.min(n,K.TAA_SLOTS-1),edit_frame:this.editFrame,change_frame:this.changeFrame,jitter_x:e[0],jitter_y:e[1],regions_x:Math.ceil(t.width/8),regions_y:Math.ceil(t.height/8),ring_capacity:t.ring,denoise:1,off_own:r.own,off_lut:r.lut,off_gbuf:r.gbuf,off_gmat:r.gmat,off_emitted:r.emitted,off_taa_info:r.taaInfo,off_illum:r.illum,off_illum2:r.illum2,off_result:r.result,off_refined:r.refined,off_region_info:r.regionInfo,off_ring:r.ringStart,off_queue_list:r.queueList})}},ll=class{device;world;pipelines;group1;params;history;lastView=``;still=0;constructor(e,t){this.device=e,this.world=t;let n=[`uniform`,`uniform`,`uniform`,`storage`,`storage`,`read-only-storage`,`storage`,`storage`];this.group1=e.createBindGroupLayout({entries:n.map((e,t)=>_c(t,e))});let r=e.createPipelineLayout({bindGroupLayouts:[t.layout,this.group1]}),i=e.createShaderModule({label:`gi.wgsl`,code:tl});this.pipelines=pc.map(t=>yc(e,{layout:r,compute:{module:i,entryPoint:t}}));let a=(t,n)=>e.createBuffer({label:t,size:n,usage:GPUBufferUsage.UNIFORM|GPUBufferUsage.COPY_DST});this.params=[a(`gi frame`,tc.size),a(`gi light`,lc.length*4),a(`gi state`,rc.size)],e.queue.writeBuffer(this.params[1],0,new Uint32Array(lc))}async render(e,t,n,r){let i=this.device,[a,o]=ol(i,n,r);e.trackChanges();let s=this.history;s&&s.plan.width===a&&s.plan.height===o&&s.chunks.join()===e.chunks.join()||(s?.destroy(),s=this.history=new cl(i,this.group1,this.params,al(a,o),[...e.chunks],e)),s.noteChanges(e);let c=hc(t,a,o,e);this.still=c===this.lastView?this.still+1:1,this.lastView=c;let l=Io(t,a,o),u=s.uploadCameras(t,l.int),d=s.frames;i.queue.writeBuffer(this.params[0],0,gc(tc,{cam_int:l.int,width:a,cam_frac:l.frac,height:o,forward:l.forward,seed:0,right:l.right,sample:d,up:l.up,history:+(d>0)})),i.queue.writeBuffer(this.params[2],0,s.info(u));let f=await Promise.all(this.pipelines.map(t=>t(e.hasInstances))),p=i.createCommandEncoder();pc.forEach((t,n)=>{if(t===`gi_atmosphere`&&d>0)return;t===`gi_trace`&&p.copyBufferToBuffer(s.words,0,s.args,0,K.ARGS_BYTES);let r=p.beginComputePass({label:t});switch(r.setPipeline(f[n]),r.setBindGroup(0,this.world.of(e)),r.setBindGroup(1,s.group),t){case`gi_atmosphere`:r.dispatchWorkgroups(K.LUT_SIZE/8,K.LUT_SIZE/8);break;case`gi_queue_scan`:r.dispatchWorkgroups(1);break;case`gi_trace`:r.dispatchWorkgroupsIndirect(s.args,K.CONTROL_TRACE_ARGS*4);break;case`gi_project`:case`gi_project_store`:r.dispatchWorkgroupsIndirect(s.args,K.CONTROL_PROJECT_ARGS*4);break;case`gi_refine`:r.dispatchWorkgroups(Math.ceil(s.plan.regions/64));break;case`gi_poses`:r.dispatchWorkgroups(Math.ceil(K.NO_ENTITY/64));break;default:r.dispatchWorkgroups(Math.ceil(a/8),Math.ceil(o/8))}r.end()}),s.frames+=1;let m=s.plan.layout.result*16;return il(new Float32Array(await wc(i,p,s.mem,m,s.staging,s.plan.pixels*16)),a,o,1,!1)}},ul=`// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the
// Rust code, the world's storage bindings.
struct WorldInfo {
    // World size in voxels.
    size: vec3<u32>,
    // Slots of the instance buffer on the device, the world's and then the local
    // instances' (records of 5 words; 0: no instance to trace).
    instance_slots: u32,
    // World size in chunks.
    chunks: vec3<u32>,
    // Cells a ray may visit before it counts as a miss.
    max_steps: u32,
}
@group(0) @binding(0) var<uniform> world_info: WorldInfo;
struct FrameInfo {
    // Camera position, integer part (floor).
    cam_int: vec3<i32>,
    // Image width in pixels.
    width: u32,
    // Camera position, fractional part in [0, 1).
    cam_frac: vec3<f32>,
    // Image height in pixels.
    height: u32,
    // View direction.
    forward: vec3<f32>,
    // The run's seed.
    seed: u32,
    // Image right, scaled by a·W/H.
    right: vec3<f32>,
    // Number of the sample this dispatch adds.
    sample: u32,
    // Image up, scaled by a.
    up: vec3<f32>,
    // 1 when a temporal pass has a history to blend with (0 for the path tracer).
    history: u32,
}
struct LightInfo {
    // Uniform sky: its radiance. Physical sky: the irradiance of the sun lighting it.
    sky: vec3<f32>,
    // 1 for the physical sky.
    sky_physical: u32,
    // Unit vector toward the sun (the sun lighting the physical sky when it is off).
    sun_dir: vec3<f32>,
    // 1 when the sun shines (its disc and its samples).
    sun_on: u32,
    // The disc's radiance.
    sun_disc: f32,
    // The weight of one disc sample: radiance times solid angle.
    sun_weight: f32,
    // 1 − cos of the disc's angular radius.
    sun_omc: f32,
    // Scattered rays after the camera ray.
    bounces: u32,
}
struct GiInfo {
    // Frames rendered in this history before this one.
    frame: u32,
    // The long-term TAA slot this frame writes (\`frame % TAA_SLOTS\`).
    taa_slot: u32,
    // Earlier frames the TAA may read (at most \`TAA_SLOTS − 1\`).
    taa_valid: u32,
    // The first frame rendered after the newest change of the materials, or of more
    // chunks than are marked one by one (0: none): the near-change rule everywhere.
    edit_frame: u32,
    // The first frame rendered after the newest change of any chunk, entity moves
    // included (0: none): the still path keeps no sample from before it.
    change_frame: u32,
    // This frame's jitter in the pixel, x (a point of a 32-point (0, 5, 2)-net).
    jitter_x: f32,
    // This frame's jitter in the pixel, y.
    jitter_y: f32,
    // 8×8 regions across.
    regions_x: u32,
    // 8×8 regions down.
    regions_y: u32,
    // Samples the sample ring holds.
    ring_capacity: u32,
    // 1 when the bilateral denoiser runs.
    denoise: u32,
    // Where each pixel's own secondary sample starts in \`mem\` (tagged with the
    // frame that traced it).
    off_own: u32,
    // Where the atmosphere table starts in \`mem\` (vec4 words; the cameras start at 0).
    off_lut: u32,
    // Where the first-hit surfaces start in \`mem\`.
    off_gbuf: u32,
    // Where the first-hit materials start in \`mem\`.
    off_gmat: u32,
    // Where the first-hit light starts in \`mem\`.
    off_emitted: u32,
    // Where the TAA's per-pixel sums and ranges start in \`mem\`.
    off_taa_info: u32,
    // Where the incoming light starts in \`mem\`.
    off_illum: u32,
    // Where the denoiser's intermediate starts in \`mem\`.
    off_illum2: u32,
    // Where the results start in \`mem\`.
    off_result: u32,
    // Where the refined samples start in \`mem\`.
    off_refined: u32,
    // Where the regions' statistics start in \`mem\`.
    off_region_info: u32,
    // Where the sample ring starts in \`mem\`.
    off_ring: u32,
    // Where the queued pixels start in \`words\`.
    off_queue_list: u32,
}
const STATE_SHIFT: u32 = 30u;
const STATE_EMPTY: u32 = 0u;
const STATE_FULL: u32 = 1u;
const STATE_MIXED: u32 = 2u;
const PAYLOAD: u32 = 1073741823u;
const MAX_MATERIAL: u32 = 32767u;
const VOXEL_SOLID: u32 = 32768u;
const CHUNK_FIELD_BITS: u32 = 5u;
const CELL_FIELD_BITS: u32 = 2u;
const KIND_DIFFUSE: u32 = 0u;
const KIND_EMISSIVE: u32 = 1u;
const KIND_METAL: u32 = 2u;
const KIND_MIRROR: u32 = 3u;
const ENTITY_SOLID: u32 = 2147483648u;
const TYPE_ALIGN: u32 = 64u;
const RECORD_WORDS: u32 = 5u;
const NO_ENTITY: u32 = 16383u;
const NODE_WORDS: u32 = 28u;
const BVH_STACK: u32 = 64u;
const BVH_LEAF: u32 = 2147483648u;
const BVH_NONE: u32 = 4294967295u;
const BVH_FAR: f32 = 1e30f;
const SURFACE_OFFSET: f32 = 0.01f;
const MIN_ALPHA: f32 = 0.001f;
const PI: f32 = 3.1415927f;
const PLANET_RADIUS: f32 = 6360000.0f;
const ATMOSPHERE_HEIGHT: f32 = 60000.0f;
const EYE_HEIGHT: f32 = 100.0f;
const VIEW_STEPS: u32 = 24u;
const LIGHT_STEPS: u32 = 6u;
const RAYLEIGH: vec3<f32> = vec3<f32>(5.802e-6f, 1.3558e-5f, 3.31e-5f);
const RAYLEIGH_SCALE: f32 = 8000.0f;
const MIE_SCATTER: f32 = 3.996e-6f;
const MIE_EXTINCTION: f32 = 4.44e-6f;
const MIE_SCALE: f32 = 1200.0f;
const MIE_G: f32 = 0.8f;
const OZONE: vec3<f32> = vec3<f32>(6.5e-7f, 1.881e-6f, 8.5e-8f);
const OZONE_CENTRE: f32 = 25000.0f;
const OZONE_HALF_WIDTH: f32 = 15000.0f;
// The first word of each buffer in \`world\`.
struct WorldOffsets {
    chunks: u32,
    blocks: u32,
    voxels: u32,
    materials: u32,
    entity_types: u32,
    entity_instances: u32,
    entity_hierarchy: u32,
    structure: u32,
}
@group(0) @binding(1) var<uniform> world_offsets: WorldOffsets;
@group(0) @binding(2) var<storage, read> world: array<u32>;
fn chunk_word(i: u32) -> u32 { return world[world_offsets.chunks + i]; }
fn block_word(i: u32) -> u32 { return world[world_offsets.blocks + i]; }
fn voxel_word(i: u32) -> u32 { return world[world_offsets.voxels + i]; }
fn material_word(i: u32) -> u32 { return world[world_offsets.materials + i]; }
fn entity_type_word(i: u32) -> u32 { return world[world_offsets.entity_types + i]; }
fn instance_word(i: u32) -> u32 { return world[world_offsets.entity_instances + i]; }
fn hierarchy_word(i: u32) -> u32 { return world[world_offsets.entity_hierarchy + i]; }
fn structure_word(i: u32) -> u32 { return world[world_offsets.structure + i]; }

// The world buffers (docs/FORMAT.md §5) and how to read their cells.
//
// Generated by naadf-client (client/src/gpu/shaders.rs) from the Rust definitions, in the
// prelude before this file:
// - the parameters \`world_info: WorldInfo\` (size in voxels and chunks, the instance
//   buffer's slots, the step budget);
// - the constants of the cell layout (STATE_*, PAYLOAD, MAX_MATERIAL, VOXEL_SOLID,
//   CHUNK_FIELD_BITS, CELL_FIELD_BITS), the material kinds (KIND_*), the entity layout
//   (ENTITY_SOLID, TYPE_ALIGN, RECORD_WORDS, NO_ENTITY), the instance hierarchy's (NODE_WORDS,
//   BVH_*) and the frame modes (MODE_*);
// - the storage bindings and the accessors \`chunk_word\`, \`block_word\`, \`voxel_word\`,
//   \`material_word\`, \`entity_type_word\`, \`instance_word\`, \`hierarchy_word\` (and
//   \`structure_word\` for the comparison traversals): a buffer larger than the adapter's
//   storage-binding limit is split across several bindings, and the accessor picks the
//   part.

// State of a chunk or block cell: STATE_EMPTY, STATE_FULL or (also for state 3)
// STATE_MIXED.
fn cell_state(c: u32) -> u32 {
    return min(c >> STATE_SHIFT, STATE_MIXED);
}

// Field \`dir\` (order −x, +x, −y, +y, −z, +z) of a packed AADF.
fn aadf_field(word: u32, dir: u32, bits: u32) -> u32 {
    return (word >> (bits * dir)) & ((1u << bits) - 1u);
}

// The index of chunk \`c\` in a world of \`chunks\` chunks (\`world_info.chunks\`). Loops read
// \`world_info\` once before they start and pass its fields: it is a storage buffer, and a
// storage read in every step is a bounds-checked load on lavapipe.
fn chunk_index(c: vec3<u32>, chunks: vec3<u32>) -> u32 {
    return c.x + chunks.x * (c.y + chunks.y * c.z);
}

fn index4(p: vec3<u32>) -> u32 {
    return p.x + 4u * p.y + 16u * p.z;
}

// Voxel \`i\` (0..64) of the voxel group starting at word \`ptr\`.
fn group_voxel(ptr: u32, i: u32) -> u32 {
    return (voxel_word(ptr + i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

// A material's entry (docs/FORMAT.md §5.4).
struct Material {
    kind: u32,
    albedo: vec3<f32>,
    emission: f32,
    roughness: f32,
}

fn material(id: u32) -> Material {
    let w0 = material_word(4u * id);
    let w1 = material_word(4u * id + 1u);
    let w2 = material_word(4u * id + 2u);
    let rg = unpack2x16float(w1);
    let be = unpack2x16float(w2);
    return Material(w0 & 3u, vec3<f32>(rg.x, rg.y, be.x), be.y, unpack2x16float(w0).y);
}

// Rays and the event model every traversal shares (world/src/traverse/ray.rs, in f32).
//
// A ray keeps its origin split into an integer part \`o_int\` and a fraction \`o_frac\` in [0, 1)
// (docs/NAADF.md §9), so precision does not depend on where in the world it starts.
// The direction \`d\` is kept exactly as given (not renormalised, which would move the line
// by an f32 rounding): times are in units of |d| and the ray's \`len\` converts them to
// distances. Every decision compares plane-crossing times from the one function \`t_at\`,
// so the traversal is a consistent walk of the event order "(t, axis), x before y before
// z at equal t"; it departs from the CPU's f64 order only where two crossings are within
// f32 rounding of each other.

// A cell bound beyond any world for unconstrained axes (the CPU walk uses 2^40, which no
// i32 holds).
const FAR_CELL: i32 = 1073741824;
const T_INF: f32 = 3.0e38;
const NO_AXIS: u32 = 3u;

struct Ray {
    o_int: vec3<i32>,
    o_frac: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    len: f32,
}

fn ray_new(o_int: vec3<i32>, o_frac: vec3<f32>, d: vec3<f32>) -> Ray {
    // The inverse of a zero component is never read: such axes never cross a plane.
    let safe = select(vec3<f32>(1.0), d, d != vec3<f32>(0.0));
    return Ray(o_int, o_frac, d, 1.0 / safe, length(d));
}

// A ray from an unsplit origin.
fn ray_from(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(o);
    return ray_new(vec3<i32>(fl), min(o - fl, vec3<f32>(0.99999994)), d);
}

// The ray's point at time \`t\`, relative to its integer origin.
fn ray_local(r: Ray, t: f32) -> vec3<f32> {
    return r.o_frac + r.d * t;
}

// A ray starting at \`p\` (relative to \`r\`'s integer origin) along \`d\`.
fn ray_at(r: Ray, p: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(p);
    return ray_new(r.o_int + vec3<i32>(fl), min(p - fl, vec3<f32>(0.99999994)), d);
}

// Time at which the ray crosses plane \`k\` of \`axis\`.
fn t_at(r: Ray, a: u32, k: i32) -> f32 {
    return (f32(k - r.o_int[a]) - r.o_frac[a]) * r.inv[a];
}

// Whether the crossing of plane \`k\` of axis \`b\` comes before the event \`(t, a)\`.
fn crossed(r: Ray, b: u32, k: i32, t: f32, a: u32) -> bool {
    let tb = t_at(r, b, k);
    return tb < t || (tb == t && b < a);
}

// The cell of axis \`b\` right after event \`(t, a)\`, known to lie in \`lo..=hi\`.
fn cell_after(r: Ray, b: u32, t: f32, a: u32, lo: i32, hi: i32) -> i32 {
    let d = r.d[b];
    if lo == hi || d == 0.0 {
        return lo;
    }
    let p = r.o_frac[b] + d * t;
    let fl = floor(p);
    var k = clamp(i32(fl) + r.o_int[b], lo, hi);
    let f = p - fl;
    // Far from a plane the floor is certain; near one, decide by crossing times.
    let tol = 4e-6 * (abs(d * t) + 1.0);
    if f > tol && f < 1.0 - tol {
        return k;
    }
    if d > 0.0 {
        while k < hi && crossed(r, b, k + 1, t, a) {
            k += 1;
        }
        while k > lo && !crossed(r, b, k, t, a) {
            k -= 1;
        }
    } else {
        while k > lo && crossed(r, b, k, t, a) {
            k -= 1;
        }
        while k < hi && !crossed(r, b, k + 1, t, a) {
            k += 1;
        }
    }
    return k;
}

// Where a ray begins inside the box [0, size): its first cell, the time it is entered and
// the axis whose plane it crossed (NO_AXIS when the origin is inside). \`ok\` is false when
// the ray misses the box.
struct Entry {
    cell: vec3<i32>,
    t: f32,
    axis: u32,
    ok: bool,
}

fn ray_entry(r: Ray, size: vec3<i32>) -> Entry {
    let start = r.o_int;
    var miss = Entry(vec3<i32>(0), 0.0, NO_AXIS, false);
    if all(start >= vec3<i32>(0)) && all(start < size) {
        return Entry(start, 0.0, NO_AXIS, true);
    }
    // The last slab-entry event, in (t, axis) order.
    var bt = 0.0;
    var ba = NO_AXIS;
    for (var a = 0u; a < 3u; a++) {
        var plane: i32;
        if start[a] < 0 {
            if r.d[a] <= 0.0 {
                return miss;
            }
            plane = 0;
        } else if start[a] >= size[a] {
            if r.d[a] >= 0.0 {
                return miss;
            }
            plane = size[a];
        } else {
            continue;
        }
        let t = t_at(r, a, plane);
        if ba == NO_AXIS || t >= bt {
            bt = t;
            ba = a;
        }
    }
    var cell = vec3<i32>(0);
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            cell[b] = select(size[b] - 1, 0, r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            cell[b] = cell_after(r, b, bt, ba, start[b], FAR_CELL);
        } else if r.d[b] < 0.0 {
            cell[b] = cell_after(r, b, bt, ba, -FAR_CELL, start[b]);
        } else {
            cell[b] = start[b];
        }
    }
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return miss;
    }
    return Entry(cell, bt, ba, true);
}

// When a ray inside the box [0, size] leaves it: the first crossing of a far plane it moves
// toward (world/src/traverse/ray.rs \`leave_time\`).
fn leave_time(r: Ray, size: vec3<i32>) -> f32 {
    var t = T_INF;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            t = min(t, t_at(r, a, select(0, size[a], r.d[a] > 0.0)));
        }
    }
    return t;
}

// Leaving the empty cuboid made of \`cell\` extended by \`skip\` cells toward the ray on each
// axis: the exit event and the cell entered by it.
struct Exit {
    t: f32,
    axis: u32,
    next: vec3<i32>,
}

fn ray_exit(r: Ray, cell: vec3<i32>, skip: vec3<i32>) -> Exit {
    var bound = vec3<i32>(0);
    var bt = T_INF;
    var ba = 0u;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] == 0.0 {
            continue;
        }
        bound[a] = select(cell[a] - skip[a], cell[a] + 1 + skip[a], r.d[a] > 0.0);
        let t = t_at(r, a, bound[a]);
        if t < bt {
            bt = t;
            ba = a;
        }
    }
    var next = cell;
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            next[b] = select(bound[b] - 1, bound[b], r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b], cell[b] + skip[b]);
        } else if r.d[b] < 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b] - skip[b], cell[b]);
        }
    }
    return Exit(bt, ba, next);
}

// Amanatides–Woo state in the same event order (ties step the lowest axis first).
struct Dda {
    cell: vec3<i32>,
    tmax: vec3<f32>,
    t: f32,
    axis: u32,
}

fn dda_start(r: Ray, e: Entry) -> Dda {
    var tmax = vec3<f32>(T_INF);
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            tmax[a] = t_at(r, a, select(e.cell[a], e.cell[a] + 1, r.d[a] > 0.0));
        }
    }
    return Dda(e.cell, tmax, e.t, e.axis);
}

fn dda_advance(r: Ray, s: ptr<function, Dda>) {
    var a = 0u;
    if (*s).tmax[1] < (*s).tmax[a] {
        a = 1u;
    }
    if (*s).tmax[2] < (*s).tmax[a] {
        a = 2u;
    }
    (*s).t = (*s).tmax[a];
    let c = (*s).cell[a] + select(-1, 1, r.d[a] > 0.0);
    (*s).cell[a] = c;
    (*s).axis = a;
    (*s).tmax[a] = t_at(r, a, select(c, c + 1, r.d[a] > 0.0));
}

// The first solid voxel along a ray (of the world, or of an entity: then voxel and normal
// are entity-local).
struct Hit {
    hit: bool,
    // The step budget ran out (counts as a miss).
    exhausted: bool,
    voxel: vec3<i32>,
    // Axis of the entry face (NO_AXIS: the origin was inside the voxel).
    axis: u32,
    // Entry-face normal (zero when the origin was inside).
    normal: vec3<i32>,
    // Time of entry, in units of the ray's |d|.
    t: f32,
    material: u32,
    steps: u32,
    // Entity id, or NO_ENTITY (generated in the prelude).
    entity: u32,
}

fn no_hit(steps: u32) -> Hit {
    return Hit(false, false, vec3<i32>(0), NO_AXIS, vec3<i32>(0), T_INF, 0u, steps, NO_ENTITY);
}

fn make_hit(r: Ray, cell: vec3<i32>, t: f32, axis: u32, material: u32, steps: u32) -> Hit {
    var n = vec3<i32>(0);
    if axis != NO_AXIS {
        n[axis] = select(1, -1, r.d[axis] > 0.0);
    }
    return Hit(true, false, cell, axis, n, t, material, steps, NO_ENTITY);
}

// One full trace: the world loop (traverse.wgsl or grid.wgsl) through the static world,
// then the instances whose world boxes the ray crosses before the world's hit or exit,
// found through their hierarchy (docs/NAADF.md §11): the GPU twin of
// world/src/traverse/entities.rs. Only the nearest entity hit (lowest id at equal times)
// survives, and only if it comes strictly before the world's hit or exit. Local instances
// (previews, markers: world/src/entity/local.rs) follow the world's records and carry the id
// NO_ENTITY, so their hits read as static geometry to everything that follows entity ids.

// How the world loop ended.
const END_HIT: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_EXHAUSTED: u32 = 3u;

struct WorldTrace {
    hit: Hit,
    end: u32,
    // When the ray entered the world, and when it hit or left it.
    t_entry: f32,
    t_end: f32,
}

// The end of a world loop whose step budget ran out at time \`t\` (entered at \`t_entry\`).
fn ran_out(t_entry: f32, t: f32) -> WorldTrace {
    var h = no_hit(world_info.max_steps);
    h.exhausted = true;
    return WorldTrace(h, END_EXHAUSTED, t_entry, t);
}

var<private> best_entity: Hit;
// The inverse rotation of \`best_entity\`'s instance.
var<private> best_rotation: vec4<f32>;
// Entity-grid cells visited (added to the step count of an entity hit).
var<private> entity_steps: u32;
// Whether the last \`trace\` returned an instance's hit (a local instance's has no entity id).
var<private> hit_instance: bool;

// Whether the world holds any instance. The host builds a pipeline for each value and
// picks the one that matches its world: a device that runs neighbouring rays in lock step
// may run code that no ray takes, and without instances none of the walk is compiled.
override HAS_INSTANCES: bool = true;

// How many instances the walk finds before it stops to test them.
const INSTANCE_BATCH: u32 = 8u;

// The walk's node stack and found instances, at module scope, so that an invocation holds
// (and zeroes) one of each rather than one for every trace inlined into it.
var<private> bvh_stack: array<u32, BVH_STACK>;
var<private> found_t: array<f32, INSTANCE_BATCH>;
var<private> found_slot: array<u32, INSTANCE_BATCH>;

// Walks the instance hierarchy (world/src/entity/bvh.rs: four-wide nodes of NODE_WORDS
// words, the children's f32 boxes axis by axis, then their references) and tests every
// instance whose box the ray is inside at some t in [t_lo, t_hi] (or up to the best entity
// hit so far). Boxes are padded and rounded outward, so the f32 test never rejects an
// instance the ray can hit. The walk gathers up to INSTANCE_BATCH instances, then tests them
// in the order the ray enters their boxes, stopping at a box that starts after the best hit,
// and goes on while nodes are left. Testing outside the walk's loop keeps that loop small,
// which is what costs on a device that runs neighbouring rays in lock step. With \`any_hit\`
// it returns at the first hit before \`t_hi\`.
fn find_instances(r: Ray, t_lo: f32, t_hi: f32, any_hit: bool) {
    // The world loop says whether its structure is traced with entities: the comparison
    // trees hold geometry only.
    if !TRACES_ENTITIES || !HAS_INSTANCES || world_info.instance_slots == 0u {
        return;
    }
    // 1/d, with ±FAR for axes the ray does not move along.
    let inv = select(1.0 / r.d, select(vec3<f32>(BVH_FAR), vec3<f32>(-BVH_FAR), r.d < vec3<f32>(0.0)), r.d == vec3<f32>(0.0));
    let o = vec3<f32>(r.o_int);
    bvh_stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        var far_limit = t_hi * 1.000001 + 1e-3;
        if best_entity.hit {
            far_limit = min(far_limit, best_entity.t * 1.000001 + 1e-3);
        }
        // A node adds at most four instances, so one is taken while four places are left.
        var found = 0u;
        while sp > 0u && found + 4u <= INSTANCE_BATCH {
            sp -= 1u;
            let base = bvh_stack[sp] * NODE_WORDS;
            // The four lanes at once, axis by axis.
            let tx0 = ((node_lanes(base) - o.x) - r.o_frac.x) * inv.x;
            let tx1 = ((node_lanes(base + 4u) - o.x) - r.o_frac.x) * inv.x;
            let ty0 = ((node_lanes(base + 8u) - o.y) - r.o_frac.y) * inv.y;
            let ty1 = ((node_lanes(base + 12u) - o.y) - r.o_frac.y) * inv.y;
            let tz0 = ((node_lanes(base + 16u) - o.z) - r.o_frac.z) * inv.z;
            let tz1 = ((node_lanes(base + 20u) - o.z) - r.o_frac.z) * inv.z;
            let near = max(vec4<f32>(t_lo - 1e-3), max(min(tx0, tx1), max(min(ty0, ty1), min(tz0, tz1))));
            let far = min(vec4<f32>(far_limit), min(max(tx0, tx1), min(max(ty0, ty1), max(tz0, tz1))));
            let child = vec4<u32>(hierarchy_word(base + 24u), hierarchy_word(base + 25u), hierarchy_word(base + 26u), hierarchy_word(base + 27u));
            let entered = !(near > far) & (child != vec4<u32>(BVH_NONE));
            // Each lane in turn: no loop, so that no lane's index is dynamic.
            if entered.x {
                keep_lane(child.x, near.x, &sp, &found);
            }
            if entered.y {
                keep_lane(child.y, near.y, &sp, &found);
            }
            if entered.z {
                keep_lane(child.z, near.z, &sp, &found);
            }
            if entered.w {
                keep_lane(child.w, near.w, &sp, &found);
            }
        }
        // Nearest box first, until one starts after the best hit (whose own box started no
        // later: the boxes are padded beyond the f32 test's rounding).
        for (var left = found; left > 0u; left--) {
            var k = 0u;
            for (var j = 1u; j < left; j++) {
                if found_t[j] < found_t[k] {
                    k = j;
                }
            }
            if best_entity.hit && found_t[k] > best_entity.t {
                break;
            }
            test_instance(r, found_slot[k] * RECORD_WORDS, t_lo);
            if any_hit && best_entity.hit && best_entity.t < t_hi {
                return;
            }
            found_t[k] = found_t[left - 1u];
            found_slot[k] = found_slot[left - 1u];
        }
    }
}

// Keeps a lane the ray enters at \`near\`: an instance among the found ones, or a node on the
// stack.
fn keep_lane(c: u32, near: f32, sp: ptr<function, u32>, found: ptr<function, u32>) {
    if (c & BVH_LEAF) != 0u {
        found_t[*found] = near;
        found_slot[*found] = c & ~BVH_LEAF;
        *found += 1u;
    } else if *sp < BVH_STACK {
        bvh_stack[*sp] = c;
        *sp += 1u;
    }
}

// Four lanes' planes of one axis, from word \`at\` of the hierarchy.
fn node_lanes(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4<u32>(hierarchy_word(at), hierarchy_word(at + 1u), hierarchy_word(at + 2u), hierarchy_word(at + 3u)));
}

// Decodes a smallest-three quaternion (world/src/entity/pack.rs).
fn decode_quat(w0: u32, w1: u32) -> vec4<f32> {
    let s = vec3<f32>(vec3<u32>(w0 & 0x3FFFu, (w0 >> 14u) & 0x3FFFu, (w0 >> 28u) | ((w1 & 0x3FFu) << 4u)));
    let small = (s - 8192.0) / 8192.0;
    let rest = sqrt(max(1.0 - dot(small, small), 0.0));
    let k = (w1 >> 10u) & 3u;
    if k == 0u {
        return vec4<f32>(rest, small.x, small.y, small.z);
    } else if k == 1u {
        return vec4<f32>(small.x, rest, small.y, small.z);
    } else if k == 2u {
        return vec4<f32>(small.x, small.y, rest, small.z);
    }
    return vec4<f32>(small, rest);
}

// Rotates \`v\` by the unit quaternion \`q = (x, y, z, w)\`.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// An instance record's position in 1/128 voxel (record words 0 and 1).
fn record_position(dx: u32, dy: u32) -> vec3<u32> {
    return vec3<u32>(dx & 0x1FFFFFu, (dx >> 21u) | (((dy >> 21u) & 0xFFu) << 11u), dy & 0x1FFFFFu);
}

// An instance record's entity id (record word 4).
fn record_id(e: u32) -> u32 {
    return e & 0x3FFFu;
}

// Tests the instance record at word \`at\` against the ray; keeps the nearest entity hit.
fn test_instance(r: Ray, at: u32, t_lo: f32) {
    let dx = instance_word(at);
    let dy = instance_word(at + 1u);
    let dz = instance_word(at + 2u);
    let dw = instance_word(at + 3u);
    let e = instance_word(at + 4u);
    let id = record_id(e);
    let size = vec3<u32>((e >> 14u) & 0x7Fu, (e >> 21u) & 0x7Fu, ((e >> 28u) & 0xFu) | (((dy >> 29u) & 7u) << 4u));
    let pos = record_position(dx, dy);
    var limit = T_INF;
    var equal_ok = false;
    if best_entity.hit {
        limit = best_entity.t;
        equal_ok = id < best_entity.entity;
    }
    // The entity lies within |size| of its local-origin corner: reject rays that pass
    // farther (with slack for f32), before transforming anything.
    let rel = vec3<f32>(r.o_int - vec3<i32>(pos >> vec3<u32>(7u))) + (r.o_frac - vec3<f32>(pos & vec3<u32>(127u)) / 128.0);
    let tc = -dot(rel, r.d) / (r.len * r.len);
    let radius = (length(vec3<f32>(size)) + 0.01) / r.len;
    let closest = rel + r.d * tc;
    if dot(closest, closest) > radius * radius * r.len * r.len || tc + radius < t_lo || tc - radius > limit {
        return;
    }
    let q = decode_quat(dz, dw & 0xFFFu);
    let local = ray_from(rotate(q, rel), rotate(q, r.d));
    let isize = vec3<i32>(size);
    let entry = ray_entry(local, isize);
    if !entry.ok {
        return;
    }
    let base = (dw >> 12u) * TYPE_ALIGN;
    var s = dda_start(local, entry);
    loop {
        entity_steps += 1u;
        if s.t > limit || (s.t == limit && !equal_ok) {
            return;
        }
        if s.t >= t_lo {
            let c = vec3<u32>(s.cell);
            let v = entity_type_word(base + c.x + size.x * (c.y + size.y * c.z));
            if (v & ENTITY_SOLID) != 0u {
                var h = make_hit(local, s.cell, s.t, s.axis, v & MAX_MATERIAL, 0u);
                h.entity = id;
                best_entity = h;
                best_rotation = q;
                return;
            }
        }
        dda_advance(local, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= isize) {
            return;
        }
    }
}

// The world-space normal of the hit the last \`trace\` returned (entity-local normals are
// rotated back to the world).
fn world_normal(h: Hit) -> vec3<f32> {
    let n = vec3<f32>(h.normal);
    if !hit_instance {
        return n;
    }
    return rotate(conjugate(best_rotation), n);
}

// Clears the entity state of the last trace and runs the world loop: how a trace starts.
fn world_first(r: Ray) -> WorldTrace {
    entity_steps = 0u;
    best_entity = no_hit(0u);
    hit_instance = false;
    return world_loop(r);
}

// Traces \`r\` through the world and its entities.
fn trace(r: Ray) -> Hit {
    let w = world_first(r);
    if w.end == END_MISSED || w.end == END_EXHAUSTED {
        return w.hit;
    }
    find_instances(r, w.t_entry, w.t_end, false);
    if best_entity.hit && best_entity.t < w.t_end {
        hit_instance = true;
        var h = best_entity;
        h.steps = w.hit.steps + entity_steps;
        return h;
    }
    var h = w.hit;
    h.steps += entity_steps;
    return h;
}

// Whether \`trace(r)\` would hit (\`x\`) and whether it would run out of steps (\`y\`), for rays
// that only ask whether something is in the way (shadow rays): a ray that hits the world
// needs no instance walk, and one that leaves it stops walking at the first instance hit.
fn occlusion(r: Ray) -> vec2<bool> {
    let w = world_first(r);
    if w.end != END_LEFT {
        return vec2<bool>(w.hit.hit, w.hit.exhausted);
    }
    find_instances(r, w.t_entry, w.t_end, true);
    return vec2<bool>(best_entity.hit && best_entity.t < w.t_end, false);
}

// The world loop over the chunk → block → voxel hierarchy (docs/NAADF.md §9), with
// AADF jumps (\`USE_AADF\`, the \`naadf\` method) or without (\`nodf\`): the GPU twin of
// world/src/traverse/hierarchy.rs. It sees the static world alone: entities are found
// afterwards, through their hierarchy (trace.wgsl).

override USE_AADF: bool = true;
// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;


fn to_edge(c: u32, neg: bool, edge: u32) -> i32 {
    let m = c & (edge - 1u);
    return i32(select(edge - 1u - m, m, neg));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing = vec3<u32>(0u, 2u, 4u) + select(vec3<u32>(0u), vec3<u32>(1u), r.d > vec3<f32>(0.0));
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(cell);
        let chunk = chunk_word(chunk_index(p >> vec3<u32>(4u), chunks));
        var skip = vec3<i32>(0);
        let cs = cell_state(chunk);
        if cs == STATE_FULL {
            return WorldTrace(make_hit(r, cell, t, axis, chunk & MAX_MATERIAL, steps), END_HIT, entry.t, t);
        } else if cs == STATE_EMPTY {
            for (var a = 0u; a < 3u; a++) {
                skip[a] = to_edge(p[a], neg[a], 16u);
                if USE_AADF {
                    skip[a] += 16 * i32(aadf_field(chunk, facing[a], CHUNK_FIELD_BITS));
                }
            }
        } else {
            let block = block_word((chunk & PAYLOAD) + index4((p >> vec3<u32>(2u)) & vec3<u32>(3u)));
            let bs = cell_state(block);
            if bs == STATE_FULL {
                return WorldTrace(make_hit(r, cell, t, axis, block & MAX_MATERIAL, steps), END_HIT, entry.t, t);
            } else if bs == STATE_EMPTY {
                for (var a = 0u; a < 3u; a++) {
                    skip[a] = to_edge(p[a], neg[a], 4u);
                    if USE_AADF {
                        skip[a] += 4 * i32(aadf_field(block, facing[a], CELL_FIELD_BITS));
                    }
                }
            } else {
                let v = group_voxel(block & PAYLOAD, index4(p & vec3<u32>(3u)));
                if (v & VOXEL_SOLID) != 0u {
                    return WorldTrace(make_hit(r, cell, t, axis, v & MAX_MATERIAL, steps), END_HIT, entry.t, t);
                }
                if USE_AADF {
                    for (var a = 0u; a < 3u; a++) {
                        skip[a] = i32(aadf_field(v, facing[a], CELL_FIELD_BITS));
                    }
                }
            }
        }
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            // An AADF box may reach beyond the world: the ray left it at the world's edge.
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, min(ex.t, leave_time(r, dims)));
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

// The samples of the lit passes: random streams (client/src/light/rng.rs), one per sample
// of each pixel, seeded from the run's seed, the pixel's index and the sample's number
// only; and the jittered camera ray of a sample.

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The stream of sample \`sample\` of pixel \`pixel\` under \`seed\`.
fn rng_new(seed: u32, pixel: u32, sample: u32) -> u32 {
    return pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(sample)));
}

// A uniform number in [0, 1) with 24 random bits.
fn rng_next(state: ptr<function, u32>) -> f32 {
    *state = pcg_hash(*state);
    return f32(*state >> 8u) * (1.0 / 16777216.0);
}

// The stream of sample \`sample\` of pixel \`pixel\`, after its first two draws: where in the
// pixel the sample's camera ray goes (uniform in [0, 1)²).
struct PixelStream {
    rng: u32,
    jitter: vec2<f32>,
}

fn pixel_stream(seed: u32, pixel: u32, sample: u32) -> PixelStream {
    var rng = rng_new(seed, pixel, sample);
    let jx = rng_next(&rng);
    let jy = rng_next(&rng);
    return PixelStream(rng, vec2<f32>(jx, jy));
}

// The camera's (unnormalised) direction through point \`jitter\` ([0, 1)²) of pixel \`gid\` of
// frame \`f\` (docs/CAMERA.md, with \`px + jitter.x\` for \`px + 0.5\`).
fn camera_dir(f: FrameInfo, gid: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let sx = 2.0 * (f32(gid.x) + jitter.x) / f32(f.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + jitter.y) / f32(f.height);
    return f.forward + sx * f.right + sy * f.up;
}

// The light model of the lit modes (docs/RENDERING.md §3a): the physical sky, the sun,
// BRDF sampling and one path's radiance. The GPU twin of client/src/light/ (sky.rs,
// scatter.rs, cpu.rs), written operation by operation like it so that the two path
// tracers agree up to rounding. Needs random.wgsl before it.
//
// The pass binds \`light: LightInfo\` (generated in the prelude from the Rust \`LightInfo\`),
// and declares \`DIFFUSE_TIER\` and \`diffuse_tier\` (no_tier.wgsl, or a lighting tier such as
// roma.wgsl) for \`path_step\`.

// PI, SURFACE_OFFSET (how far scattered and shadow rays start off the surface),
// MIN_ALPHA (the smallest GGX α a metal is traced with) and the physical sky's constants
// (PLANET_RADIUS, VIEW_STEPS, RAYLEIGH, MIE_G, OZONE, …) come from the prelude, generated
// from their Rust definitions in client/src/light/ (mod.rs, scatter.rs, sky.rs).

// ---- The physical sky (sky.rs) ----

// Distance from height \`h\` along zenith cosine \`mu\` to the sphere at height \`top\`; a
// negative value when it is not reached going forward.
fn sphere_distance(h: f32, mu: f32, top: f32) -> f32 {
    let r = PLANET_RADIUS + h;
    let disc = (top - h) * (2.0 * PLANET_RADIUS + top + h) + r * r * mu * mu;
    if disc < 0.0 {
        return -1.0;
    }
    let s = sqrt(disc);
    let far = -r * mu + s;
    if far < 0.0 {
        return -1.0;
    }
    let near = -r * mu - s;
    return select(far, near, near > 0.0);
}

struct Medium {
    sigma: vec3<f32>,
    rayleigh: f32,
    mie: f32,
}

fn medium(h: f32) -> Medium {
    let rayleigh = exp(-h / RAYLEIGH_SCALE);
    let mie = exp(-h / MIE_SCALE);
    let ozone = max(1.0 - abs(h - OZONE_CENTRE) / OZONE_HALF_WIDTH, 0.0);
    return Medium(RAYLEIGH * rayleigh + MIE_EXTINCTION * mie + OZONE * ozone, rayleigh, mie);
}

fn sun_transmittance(h: f32, mu: f32) -> vec3<f32> {
    if mu < 0.0 && sphere_distance(h, mu, 0.0) >= 0.0 {
        return vec3<f32>(0.0);
    }
    let length = max(sphere_distance(h, mu, ATMOSPHERE_HEIGHT), 0.0);
    let dt = length / f32(LIGHT_STEPS);
    let r = PLANET_RADIUS + h;
    var depth = vec3<f32>(0.0);
    for (var i = 0u; i < LIGHT_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let hi = sqrt(t * t + 2.0 * r * mu * t + r * r) - PLANET_RADIUS;
        depth += medium(hi).sigma * dt;
    }
    return exp(-depth);
}

// Sky radiance along unit \`dir\` for unit sun direction \`sun\`, per unit of irradiance.
fn sky_physical(dir: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let mu = dir.y;
    let nu = dot(dir, sun);
    let h0 = EYE_HEIGHT;
    let r0 = PLANET_RADIUS + h0;
    var length = sphere_distance(h0, mu, 0.0);
    if !(mu < 0.0 && length >= 0.0) {
        length = max(sphere_distance(h0, mu, ATMOSPHERE_HEIGHT), 0.0);
    }
    let dt = length / f32(VIEW_STEPS);
    let phase_r = 3.0 / (16.0 * PI) * (1.0 + nu * nu);
    let g2 = MIE_G * MIE_G;
    let phase_m = (1.0 - g2) / (4.0 * PI * pow(1.0 + g2 - 2.0 * MIE_G * nu, 1.5));
    var depth = vec3<f32>(0.0);
    var inscatter = vec3<f32>(0.0);
    for (var i = 0u; i < VIEW_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let r = sqrt(t * t + 2.0 * r0 * mu * t + r0 * r0);
        let h = r - PLANET_RADIUS;
        let mu_sun = (r0 * sun.y + t * nu) / r;
        let m = medium(h);
        let to_sun = sun_transmittance(h, mu_sun);
        let view = exp(-(depth + 0.5 * m.sigma * dt));
        let scatter = RAYLEIGH * m.rayleigh * phase_r + MIE_SCATTER * m.mie * phase_m;
        inscatter += view * to_sun * scatter * dt;
        depth += m.sigma * dt;
    }
    return inscatter;
}

// The sky along unit \`d\`, evaluated directly (no disc).
fn sky_direct(d: vec3<f32>) -> vec3<f32> {
    if light.sky_physical != 0u {
        return sky_physical(d, light.sun_dir) * light.sky;
    }
    return light.sky;
}

// The sky along unit \`d\`; with \`disc\`, the sun's disc too. \`sky_base(d)\` is the including
// pass's choice: \`sky_direct\` (the path tracer) or the atmosphere table (\`gi\`).
fn sky_radiance(d: vec3<f32>, disc: bool) -> vec3<f32> {
    var l = sky_base(d);
    if disc {
        l += sun_disc(d);
    }
    return l;
}

// The sun's disc along unit \`d\` (0 off the disc, or with the sun off).
fn sun_disc(d: vec3<f32>) -> vec3<f32> {
    if light.sun_on != 0u && 1.0 - dot(d, light.sun_dir) <= light.sun_omc {
        return vec3<f32>(light.sun_disc);
    }
    return vec3<f32>(0.0);
}

// ---- Scattering (scatter.rs) ----

struct Basis {
    t: vec3<f32>,
    b: vec3<f32>,
}

fn basis(n: vec3<f32>) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

fn sample_cosine(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let f = basis(n);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (r * cos(phi)) + f.b * (r * sin(phi)) + n * sqrt(max(1.0 - u.x, 0.0)));
}

fn sample_cone(axis: vec3<f32>, omc: f32, u: vec2<f32>) -> vec3<f32> {
    let f = basis(axis);
    let x = u.x * omc;
    let c = 1.0 - x;
    let s = sqrt(max(x * (2.0 - x), 0.0));
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (s * cos(phi)) + f.b * (s * sin(phi)) + axis * c);
}

fn schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let k = 1.0 - clamp(c, 0.0, 1.0);
    let k2 = k * k;
    return f0 + (vec3<f32>(1.0) - f0) * (k2 * k2 * k);
}

fn smith_lambda(alpha: f32, c: f32) -> f32 {
    let c2 = max(c * c, 1e-12);
    let tan2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (-1.0 + sqrt(1.0 + alpha * alpha * tan2));
}

fn ggx_d(alpha: f32, c: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = c * c * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

fn ggx(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, alpha: f32, f0: vec3<f32>) -> vec3<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if co <= 0.0 || ci <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = normalize(wo + wi);
    let g2 = 1.0 / (1.0 + smith_lambda(alpha, co) + smith_lambda(alpha, ci));
    return schlick(f0, dot(wo, h)) * (ggx_d(alpha, dot(n, h)) * g2 / (4.0 * co * ci));
}

struct Scattered {
    dir: vec3<f32>,
    weight: vec3<f32>,
}

fn ggx_sample(n: vec3<f32>, wo: vec3<f32>, alpha: f32, f0: vec3<f32>, u: vec2<f32>) -> Scattered {
    let f = basis(n);
    let v = vec3<f32>(dot(wo, f.t), dot(wo, f.b), dot(wo, n));
    let vh = normalize(vec3<f32>(alpha * v.x, alpha * v.y, v.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = t1 * p1 + t2 * p2 + vh * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    let m = normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    let lwi = m * (2.0 * dot(v, m)) - v;
    let wi = normalize(f.t * lwi.x + f.b * lwi.y + n * lwi.z);
    let lo = smith_lambda(alpha, v.z);
    let li = smith_lambda(alpha, lwi.z);
    return Scattered(wi, schlick(f0, dot(v, m)) * ((1.0 + lo) / (1.0 + lo + li)));
}

// ---- Paths (cpu.rs) ----

// Whether a shadow ray meets anything before leaving the world (a ray out of cells counts
// as blocked).
fn blocked(r: Ray, p: vec3<f32>, dir: vec3<f32>) -> bool {
    return any(occlusion(ray_at(r, p, dir)));
}

// One sample of the sun's disc seen from \`p\` (relative to \`r\`'s integer origin, just off a
// surface of normal \`n\`): its direction, and the irradiance it brings (\`E·cosθ\`-weighted)
// when it is above the surface and unblocked, else 0. Two random numbers are drawn
// whenever the sun is on (cpu.rs \`sun_sample\`).
struct SunSample {
    dir: vec3<f32>,
    irradiance: f32,
}

fn sun_sample(r: Ray, p: vec3<f32>, n: vec3<f32>, rng: ptr<function, u32>) -> SunSample {
    if light.sun_on == 0u {
        return SunSample(vec3<f32>(0.0), 0.0);
    }
    let u = vec2<f32>(rng_next(rng), rng_next(rng));
    let wi = sample_cone(light.sun_dir, light.sun_omc, u);
    let c = dot(n, wi);
    if c > 0.0 && !blocked(r, p, wi) {
        return SunSample(wi, c * light.sun_weight);
    }
    return SunSample(wi, 0.0);
}

// One step of a path: what it adds and whether it goes on.
struct PathState {
    r: Ray,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    sees_disc: bool,
    alive: bool,
    // The normal of the first surface met (zero until then).
    first_normal: vec3<f32>,
}

// Follows the path in \`s\` to its next surface: adds the light found there and, when
// \`scatter\`, picks the next ray (or ends the path). Returns the distance to the surface
// (−1 when the ray found none).
fn path_step(s: ptr<function, PathState>, scatter: bool, rng: ptr<function, u32>) -> f32 {
    let r = (*s).r;
    let h = trace(r);
    let d = r.d / r.len;
    (*s).alive = false;
    if h.exhausted {
        return -1.0;
    }
    if !h.hit {
        (*s).radiance += (*s).throughput * sky_radiance(d, (*s).sees_disc);
        return -1.0;
    }
    let distance = h.t * r.len;
    if h.axis == NO_AXIS {
        return distance;
    }
    // Before any other trace: world_normal reads the last trace's entity rotation.
    let n = world_normal(h);
    if all((*s).first_normal == vec3<f32>(0.0)) {
        (*s).first_normal = n;
    }
    let m = material(h.material);
    if m.kind == KIND_EMISSIVE {
        (*s).radiance += (*s).throughput * m.albedo * m.emission;
    }
    // A lighting tier (\`roma\`, \`irradiance\`) lights diffuse and emissive surfaces itself,
    // and the path ends there; mirrors and metals scatter on.
    if DIFFUSE_TIER && m.kind != KIND_MIRROR && m.kind != KIND_METAL {
        let surface = vec3<f32>(r.o_int) + ray_local(r, h.t);
        (*s).radiance += (*s).throughput * diffuse_tier(h, surface, n, m.albedo, rng);
        return distance;
    }
    if !scatter {
        return distance;
    }
    let p = ray_local(r, h.t) + n * SURFACE_OFFSET;
    var next: Scattered;
    if m.kind == KIND_MIRROR {
        (*s).sees_disc = true;
        next = Scattered(d - n * (2.0 * dot(d, n)), m.albedo);
    } else {
        let wo = -d;
        let alpha = max(m.roughness, MIN_ALPHA);
        let sun = sun_sample(r, p, n, rng);
        if sun.irradiance > 0.0 {
            var f = m.albedo / PI;
            if m.kind == KIND_METAL {
                f = ggx(n, wo, sun.dir, alpha, m.albedo);
            }
            (*s).radiance += (*s).throughput * f * sun.irradiance;
        }
        let u = vec2<f32>(rng_next(rng), rng_next(rng));
        (*s).sees_disc = false;
        if m.kind == KIND_METAL {
            next = ggx_sample(n, wo, alpha, m.albedo, u);
        } else {
            next = Scattered(sample_cosine(n, u), m.albedo);
        }
    }
    if dot(next.dir, n) > 0.0 {
        (*s).throughput *= next.weight;
        (*s).r = ray_at(r, p, next.dir);
        (*s).alive = true;
    }
    return distance;
}

// One path: the radiance it brought back, the distance from its origin to the first
// surface (−1 for the sky) and that surface's normal.
struct PathSample {
    radiance: vec3<f32>,
    distance: f32,
    normal: vec3<f32>,
}

// The radiance arriving along \`primary\` when the path may scatter \`bounces\` more times,
// drawing from \`rng\`. \`sees_disc\`: whether the ray sees the sun's disc (camera and mirror
// rays do; rays scattered by other surfaces get the sun by next-event estimation instead).
fn path_radiance(primary: Ray, bounces: u32, sees_disc: bool, rng: ptr<function, u32>) -> PathSample {
    var s = PathState(primary, vec3<f32>(0.0), vec3<f32>(1.0), sees_disc, true, vec3<f32>(0.0));
    let distance = path_step(&s, bounces > 0u, rng);
    for (var bounce = 1u; bounce <= bounces && s.alive; bounce++) {
        path_step(&s, bounce < bounces, rng);
    }
    return PathSample(s.radiance, distance, s.first_normal);
}

// ROMA visibility for the diffuse surfaces of \`roma\` (docs/RENDERING.md §3d): the GPU twin
// of client/src/light/roma/, which states the rules (directions, maps, windows, levels,
// the walk). Included by the ROMA sample pass before light.wgsl's paths, whose
// \`path_step\` hands every diffuse and emissive surface to \`diffuse_tier\`.
//
// \`RomaInfo\`, \`RomaWindow\` and the ROMA_* constants are generated by client/src/gpu/roma.rs.
// Windows are indexed \`map * ROMA_LEVELS + level\`; a window's tiles lie at
// \`first_tile + slot\`, slot being the tile's coordinates modulo ROMA_WINDOW_TILES (the
// window moves with the camera by rebuilding only the tiles it gains).

@group(1) @binding(3) var<uniform> roma: RomaInfo;
@group(1) @binding(4) var<storage, read> roma_windows: array<RomaWindow>;
@group(1) @binding(5) var<storage, read> roma_bits: array<u32>;

const DIFFUSE_TIER: bool = true;

// Column (x, y) of window \`win\` in tile row \`tz\` (0 outside the window).
fn roma_column(win: u32, x: i32, y: i32, tz: i32) -> u32 {
    let w = roma_windows[win];
    let tile = vec3<i32>(x >> ROMA_TILE_SHIFT, y >> ROMA_TILE_SHIFT, tz);
    let rel = tile - w.base;
    if any(rel < vec3<i32>(0)) || any(rel >= vec3<i32>(i32(ROMA_WINDOW_TILES))) {
        return 0u;
    }
    let m = vec3<u32>(tile & vec3<i32>(i32(ROMA_WINDOW_TILES) - 1));
    let slot = m.x + ROMA_WINDOW_TILES * (m.y + ROMA_WINDOW_TILES * m.z);
    let col = u32(x & (ROMA_TILE - 1)) + u32(ROMA_TILE) * u32(y & (ROMA_TILE - 1));
    return roma_bits[(w.first_tile + slot) * ROMA_TILE_WORDS + col];
}

// Whether column (x, y) of window \`win\` has an occupied cell from depth \`lo\` to \`hi\`.
fn roma_column_any(win: u32, x: i32, y: i32, lo: i32, hi: i32) -> bool {
    for (var tz = lo >> ROMA_TILE_SHIFT; tz <= (hi >> ROMA_TILE_SHIFT); tz++) {
        let first = max(lo - tz * ROMA_TILE, 0);
        let last = min(hi - tz * ROMA_TILE, ROMA_TILE - 1);
        let mask = (0xFFFFFFFFu >> u32(31 - last + first)) << u32(first);
        if (roma_column(win, x, y, tz) & mask) != 0u {
            return true;
        }
    }
    return false;
}

// Map coordinates of world vector \`p\` in window \`w\`, in its cells.
fn roma_to_map(w: RomaWindow, p: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot(w.t, p), dot(w.b, p), dot(w.w, p)) / w.cell;
}

// How a walk through one window ended: \`hit\`, or clear up to \`t\`.
struct RomaWalk {
    hit: bool,
    t: f32,
}

// One axis of the column walk: when it first leaves column \`i\` (from map coordinate \`p\`,
// moving \`v\` cells per voxel), the time between its crossings, and its step.
struct RomaAxis {
    next: f32,
    delta: f32,
    step: i32,
}

fn roma_axis(p: f32, i: i32, v: f32) -> RomaAxis {
    if v > 0.0 {
        return RomaAxis((f32(i + 1) - p) / v, 1.0 / v, 1);
    } else if v < 0.0 {
        return RomaAxis((f32(i) - p) / v, -1.0 / v, -1);
    }
    return RomaAxis(ROMA_FAR, ROMA_FAR, 0);
}

// Walks \`o + t·d\` for t in [t0, t1] across the texel columns of window \`win\`.
fn roma_walk(win: u32, o: vec3<f32>, d: vec3<f32>, t0: f32, t1: f32) -> RomaWalk {
    let w = roma_windows[win];
    let q = roma_to_map(w, o);
    let e = roma_to_map(w, d);
    let lo = vec3<f32>(w.base * ROMA_TILE);
    let hi = lo + f32(i32(ROMA_WINDOW_TILES) * ROMA_TILE);
    var ta = t0;
    var tb = t1;
    for (var a = 0u; a < 3u; a++) {
        if e[a] == 0.0 {
            if q[a] < lo[a] || q[a] >= hi[a] {
                return RomaWalk(false, t0);
            }
            continue;
        }
        let s0 = (lo[a] - q[a]) / e[a];
        let s1 = (hi[a] - q[a]) / e[a];
        ta = max(ta, min(s0, s1));
        tb = min(tb, max(s0, s1));
    }
    if ta >= tb {
        return RomaWalk(false, t0);
    }
    let start = q + e * ta;
    var x = i32(floor(start.x));
    var y = i32(floor(start.y));
    let ax = roma_axis(q.x, x, e.x);
    let ay = roma_axis(q.y, y, e.y);
    var next = vec2<f32>(ax.next, ay.next);
    let delta = vec2<f32>(ax.delta, ay.delta);
    let step = vec2<i32>(ax.step, ay.step);
    var t_in = ta;
    for (var i = 0u; i < ROMA_MAX_COLUMNS; i++) {
        let t_out = min(min(next.x, next.y), tb);
        let wa = q.z + e.z * t_in;
        let wb = q.z + e.z * t_out;
        if roma_column_any(win, x, y, i32(floor(min(wa, wb))), i32(floor(max(wa, wb)))) {
            return RomaWalk(true, t_in);
        }
        if t_out >= tb {
            break;
        }
        if next.x <= next.y {
            x += step.x;
            next.x += delta.x;
        } else {
            y += step.y;
            next.y += delta.y;
        }
        t_in = t_out;
    }
    return RomaWalk(false, tb);
}

// The finest level that serves world point \`p\` (ROMA_LEVELS beyond them all).
fn roma_level(p: vec3<f32>) -> u32 {
    let d = abs(p - roma.camera);
    let m = max(d.x, max(d.y, d.z));
    for (var l = 0u; l < ROMA_LEVELS; l++) {
        if m < ROMA_REACH * roma_windows[l].cell {
            return l;
        }
    }
    return ROMA_LEVELS;
}

// Whether the ray from surface point \`p\` (normal \`n\`) along unit \`d\` is clear for \`range\`
// voxels through map \`map\`.
fn roma_clear(map: u32, p: vec3<f32>, n: vec3<f32>, d: vec3<f32>, range: f32) -> bool {
    let level = roma_level(p);
    if level >= ROMA_LEVELS {
        return true;
    }
    let o = p + n * (roma_windows[level].offset * roma_windows[level].cell);
    var t = 0.0;
    for (var l = level; l < ROMA_LEVELS; l++) {
        var start = 0.0;
        if l != level {
            start = max(t, 2.0 * roma_windows[l].cell);
        }
        if start >= range {
            return true;
        }
        let walk = roma_walk(map * ROMA_LEVELS + l, o, d, start, range);
        if walk.hit {
            return false;
        }
        if walk.t >= range {
            return true;
        }
        t = walk.t;
    }
    return true;
}

// The Shirley–Chiu square point of disc point (x, y).
fn roma_inverse_concentric(x: f32, y: f32) -> vec2<f32> {
    let r = sqrt(x * x + y * y);
    var phi = atan2(y, x);
    let q = 0.25 * PI;
    if phi < -q {
        phi += 2.0 * PI;
    }
    if phi < q {
        return vec2<f32>(r, phi * r / q);
    } else if phi < 3.0 * q {
        return vec2<f32>(-(phi - 2.0 * q) * r / q, r);
    } else if phi < 5.0 * q {
        return vec2<f32>(-r, -(phi - 4.0 * q) * r / q);
    }
    return vec2<f32>((phi - 6.0 * q) * r / q, -r);
}

// The candidate map of unit direction \`d\` (of its reverse when it points down).
fn roma_stratum(d: vec3<f32>) -> u32 {
    let u = select(d, -d, d.y < 0.0);
    let ab = roma_inverse_concentric(u.x, u.z);
    let s = f32(roma.side);
    let c = min(vec2<u32>(max(floor((ab + 1.0) * 0.5 * s), vec2<f32>(0.0))), vec2<u32>(roma.side - 1u));
    return c.x + roma.side * c.y;
}

// The light a diffuse surface of \`albedo\` at world point \`p\` (normal \`n\`) reflects: sky
// through the AO range, and the sun's disc through the sun's map (CpuRoma::diffuse, the
// same four numbers drawn in the same order).
fn diffuse_tier(h: Hit, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    let u = vec2<f32>(rng_next(rng), rng_next(rng));
    let us = vec2<f32>(rng_next(rng), rng_next(rng));
    let w = sample_cosine(n, u);
    var l = vec3<f32>(0.0);
    if roma_clear(roma_stratum(w), p, n, w, roma.ao_range) {
        l += albedo * sky_base(w);
    }
    if light.sun_on != 0u {
        let ws = sample_cone(light.sun_dir, light.sun_omc, us);
        let c = dot(n, ws);
        if c > 0.0 && roma_clear(roma.directions, p, n, ws, ROMA_FAR) {
            l += albedo / PI * (c * light.sun_weight);
        }
    }
    return l;
}

// Passes \`path_trace\` (progressive path tracing, \`pathtrace\`) and \`path_sample\` (one sample
// per pixel per frame, \`baseline\`), one invocation per pixel (docs/RENDERING.md §3a, §3b).
//
// \`path_trace\`: each dispatch adds sample number \`frame.sample\` to every pixel's running
// sum; the host divides by the count. A sample's random stream depends only on (seed, pixel, sample
// number), and every pixel adds its samples in number order, so the sums are the same bit
// for bit however the dispatches are grouped into submissions.
//
// One sample per dispatch, not a loop over samples: lavapipe (Mesa 22.3) miscompiles a
// sample loop around the bounce loop around the traversal loop, and pixels silently lose
// samples.
//
// \`FrameInfo\` and \`LightInfo\` are generated in the prelude from their Rust twins.

@group(1) @binding(0) var<uniform> frame: FrameInfo;
@group(1) @binding(1) var<uniform> light: LightInfo;
// \`path_trace\`: running sums (RGB, count). \`path_sample\`: this frame's sample (RGB, and
// the distance to the first surface, −1 for the sky).
@group(1) @binding(2) var<storage, read_write> radiance: array<vec4<f32>>;

// The path tracer sees the sky as the light model defines it, direction by direction.
fn sky_base(d: vec3<f32>) -> vec3<f32> {
    return sky_direct(d);
}

// Sample \`frame.sample\` of pixel \`gid\`.
fn pixel_sample(gid: vec2<u32>) -> PathSample {
    let stream = pixel_stream(frame.seed, gid.x + gid.y * frame.width, frame.sample);
    var rng = stream.rng;
    let r = ray_new(frame.cam_int, frame.cam_frac, camera_dir(frame, gid, stream.jitter));
    return path_radiance(r, light.bounces, true, &rng);
}

@compute @workgroup_size(8, 8)
fn path_trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let s = pixel_sample(gid.xy);
    radiance[gid.x + gid.y * frame.width] += vec4<f32>(s.radiance, 1.0);
}

@compute @workgroup_size(8, 8)
fn path_sample(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let s = pixel_sample(gid.xy);
    radiance[gid.x + gid.y * frame.width] = vec4<f32>(s.radiance, s.distance);
}

const ROMA_LEVELS: u32 = 3u;
const ROMA_TILE: i32 = 32i;
const ROMA_TILE_SHIFT: u32 = 5u;
const ROMA_TILE_WORDS: u32 = 1024u;
const ROMA_WINDOW_TILES: u32 = 8u;
const ROMA_REACH: f32 = 94.0f;
const ROMA_MAX_COLUMNS: u32 = 1024u;
const ROMA_FAR: f32 = 1e30f;
struct RomaInfo {
    // The camera the windows are centred on, in voxels.
    camera: vec3<f32>,
    // How far ambient occlusion looks, in voxels.
    ao_range: f32,
    // Candidate directions per axis of the concentric square.
    side: u32,
    // Candidate directions (\`side²\`); the sun's map follows them.
    directions: u32,
    // Padding to 16 bytes.
    _pad0: u32,
    // Padding to 16 bytes.
    _pad1: u32,
}
struct RomaWindow {
    // The frame's first row.
    t: vec3<f32>,
    // The level's cell edge, in voxels.
    cell: f32,
    // The frame's second row.
    b: vec3<f32>,
    // The window's first tile in \`roma_bits\` (in tiles).
    first_tile: u32,
    // The frame's third row: the map's direction.
    w: vec3<f32>,
    // How far off a surface a ray starts, in cells of this level.
    offset: f32,
    // The window's lowest tile, per map axis.
    base: vec3<i32>,
    // Padding to 16 bytes.
    _pad: u32,
}
struct RomaJob {
    // The tile's coordinates in its map, in tiles.
    tile: vec3<i32>,
    // Its window (\`map · ROMA_LEVELS + level\`).
    window: u32,
    // 1: the tile lies outside the world, so it is cleared without sampling.
    clear: u32,
    // Padding to 16 bytes.
    _pad0: u32,
    // Padding to 16 bytes.
    _pad1: u32,
    // Padding to 16 bytes.
    _pad2: u32,
}
`,dl=`// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the
// Rust code, the world's storage bindings.
struct WorldInfo {
    // World size in voxels.
    size: vec3<u32>,
    // Slots of the instance buffer on the device, the world's and then the local
    // instances' (records of 5 words; 0: no instance to trace).
    instance_slots: u32,
    // World size in chunks.
    chunks: vec3<u32>,
    // Cells a ray may visit before it counts as a miss.
    max_steps: u32,
}
@group(0) @binding(0) var<uniform> world_info: WorldInfo;
struct FrameInfo {
    // Camera position, integer part (floor).
    cam_int: vec3<i32>,
    // Image width in pixels.
    width: u32,
    // Camera position, fractional part in [0, 1).
    cam_frac: vec3<f32>,
    // Image height in pixels.
    height: u32,
    // View direction.
    forward: vec3<f32>,
    // The run's seed.
    seed: u32,
    // Image right, scaled by a·W/H.
    right: vec3<f32>,
    // Number of the sample this dispatch adds.
    sample: u32,
    // Image up, scaled by a.
    up: vec3<f32>,
    // 1 when a temporal pass has a history to blend with (0 for the path tracer).
    history: u32,
}
struct LightInfo {
    // Uniform sky: its radiance. Physical sky: the irradiance of the sun lighting it.
    sky: vec3<f32>,
    // 1 for the physical sky.
    sky_physical: u32,
    // Unit vector toward the sun (the sun lighting the physical sky when it is off).
    sun_dir: vec3<f32>,
    // 1 when the sun shines (its disc and its samples).
    sun_on: u32,
    // The disc's radiance.
    sun_disc: f32,
    // The weight of one disc sample: radiance times solid angle.
    sun_weight: f32,
    // 1 − cos of the disc's angular radius.
    sun_omc: f32,
    // Scattered rays after the camera ray.
    bounces: u32,
}
struct GiInfo {
    // Frames rendered in this history before this one.
    frame: u32,
    // The long-term TAA slot this frame writes (\`frame % TAA_SLOTS\`).
    taa_slot: u32,
    // Earlier frames the TAA may read (at most \`TAA_SLOTS − 1\`).
    taa_valid: u32,
    // The first frame rendered after the newest change of the materials, or of more
    // chunks than are marked one by one (0: none): the near-change rule everywhere.
    edit_frame: u32,
    // The first frame rendered after the newest change of any chunk, entity moves
    // included (0: none): the still path keeps no sample from before it.
    change_frame: u32,
    // This frame's jitter in the pixel, x (a point of a 32-point (0, 5, 2)-net).
    jitter_x: f32,
    // This frame's jitter in the pixel, y.
    jitter_y: f32,
    // 8×8 regions across.
    regions_x: u32,
    // 8×8 regions down.
    regions_y: u32,
    // Samples the sample ring holds.
    ring_capacity: u32,
    // 1 when the bilateral denoiser runs.
    denoise: u32,
    // Where each pixel's own secondary sample starts in \`mem\` (tagged with the
    // frame that traced it).
    off_own: u32,
    // Where the atmosphere table starts in \`mem\` (vec4 words; the cameras start at 0).
    off_lut: u32,
    // Where the first-hit surfaces start in \`mem\`.
    off_gbuf: u32,
    // Where the first-hit materials start in \`mem\`.
    off_gmat: u32,
    // Where the first-hit light starts in \`mem\`.
    off_emitted: u32,
    // Where the TAA's per-pixel sums and ranges start in \`mem\`.
    off_taa_info: u32,
    // Where the incoming light starts in \`mem\`.
    off_illum: u32,
    // Where the denoiser's intermediate starts in \`mem\`.
    off_illum2: u32,
    // Where the results start in \`mem\`.
    off_result: u32,
    // Where the refined samples start in \`mem\`.
    off_refined: u32,
    // Where the regions' statistics start in \`mem\`.
    off_region_info: u32,
    // Where the sample ring starts in \`mem\`.
    off_ring: u32,
    // Where the queued pixels start in \`words\`.
    off_queue_list: u32,
}
const STATE_SHIFT: u32 = 30u;
const STATE_EMPTY: u32 = 0u;
const STATE_FULL: u32 = 1u;
const STATE_MIXED: u32 = 2u;
const PAYLOAD: u32 = 1073741823u;
const MAX_MATERIAL: u32 = 32767u;
const VOXEL_SOLID: u32 = 32768u;
const CHUNK_FIELD_BITS: u32 = 5u;
const CELL_FIELD_BITS: u32 = 2u;
const KIND_DIFFUSE: u32 = 0u;
const KIND_EMISSIVE: u32 = 1u;
const KIND_METAL: u32 = 2u;
const KIND_MIRROR: u32 = 3u;
const ENTITY_SOLID: u32 = 2147483648u;
const TYPE_ALIGN: u32 = 64u;
const RECORD_WORDS: u32 = 5u;
const NO_ENTITY: u32 = 16383u;
const NODE_WORDS: u32 = 28u;
const BVH_STACK: u32 = 64u;
const BVH_LEAF: u32 = 2147483648u;
const BVH_NONE: u32 = 4294967295u;
const BVH_FAR: f32 = 1e30f;
const SURFACE_OFFSET: f32 = 0.01f;
const MIN_ALPHA: f32 = 0.001f;
const PI: f32 = 3.1415927f;
const PLANET_RADIUS: f32 = 6360000.0f;
const ATMOSPHERE_HEIGHT: f32 = 60000.0f;
const EYE_HEIGHT: f32 = 100.0f;
const VIEW_STEPS: u32 = 24u;
const LIGHT_STEPS: u32 = 6u;
const RAYLEIGH: vec3<f32> = vec3<f32>(5.802e-6f, 1.3558e-5f, 3.31e-5f);
const RAYLEIGH_SCALE: f32 = 8000.0f;
const MIE_SCATTER: f32 = 3.996e-6f;
const MIE_EXTINCTION: f32 = 4.44e-6f;
const MIE_SCALE: f32 = 1200.0f;
const MIE_G: f32 = 0.8f;
const OZONE: vec3<f32> = vec3<f32>(6.5e-7f, 1.881e-6f, 8.5e-8f);
const OZONE_CENTRE: f32 = 25000.0f;
const OZONE_HALF_WIDTH: f32 = 15000.0f;
// The first word of each buffer in \`world\`.
struct WorldOffsets {
    chunks: u32,
    blocks: u32,
    voxels: u32,
    materials: u32,
    entity_types: u32,
    entity_instances: u32,
    entity_hierarchy: u32,
    structure: u32,
}
@group(0) @binding(1) var<uniform> world_offsets: WorldOffsets;
@group(0) @binding(2) var<storage, read> world: array<u32>;
fn chunk_word(i: u32) -> u32 { return world[world_offsets.chunks + i]; }
fn block_word(i: u32) -> u32 { return world[world_offsets.blocks + i]; }
fn voxel_word(i: u32) -> u32 { return world[world_offsets.voxels + i]; }
fn material_word(i: u32) -> u32 { return world[world_offsets.materials + i]; }
fn entity_type_word(i: u32) -> u32 { return world[world_offsets.entity_types + i]; }
fn instance_word(i: u32) -> u32 { return world[world_offsets.entity_instances + i]; }
fn hierarchy_word(i: u32) -> u32 { return world[world_offsets.entity_hierarchy + i]; }
fn structure_word(i: u32) -> u32 { return world[world_offsets.structure + i]; }

// The world buffers (docs/FORMAT.md §5) and how to read their cells.
//
// Generated by naadf-client (client/src/gpu/shaders.rs) from the Rust definitions, in the
// prelude before this file:
// - the parameters \`world_info: WorldInfo\` (size in voxels and chunks, the instance
//   buffer's slots, the step budget);
// - the constants of the cell layout (STATE_*, PAYLOAD, MAX_MATERIAL, VOXEL_SOLID,
//   CHUNK_FIELD_BITS, CELL_FIELD_BITS), the material kinds (KIND_*), the entity layout
//   (ENTITY_SOLID, TYPE_ALIGN, RECORD_WORDS, NO_ENTITY), the instance hierarchy's (NODE_WORDS,
//   BVH_*) and the frame modes (MODE_*);
// - the storage bindings and the accessors \`chunk_word\`, \`block_word\`, \`voxel_word\`,
//   \`material_word\`, \`entity_type_word\`, \`instance_word\`, \`hierarchy_word\` (and
//   \`structure_word\` for the comparison traversals): a buffer larger than the adapter's
//   storage-binding limit is split across several bindings, and the accessor picks the
//   part.

// State of a chunk or block cell: STATE_EMPTY, STATE_FULL or (also for state 3)
// STATE_MIXED.
fn cell_state(c: u32) -> u32 {
    return min(c >> STATE_SHIFT, STATE_MIXED);
}

// Field \`dir\` (order −x, +x, −y, +y, −z, +z) of a packed AADF.
fn aadf_field(word: u32, dir: u32, bits: u32) -> u32 {
    return (word >> (bits * dir)) & ((1u << bits) - 1u);
}

// The index of chunk \`c\` in a world of \`chunks\` chunks (\`world_info.chunks\`). Loops read
// \`world_info\` once before they start and pass its fields: it is a storage buffer, and a
// storage read in every step is a bounds-checked load on lavapipe.
fn chunk_index(c: vec3<u32>, chunks: vec3<u32>) -> u32 {
    return c.x + chunks.x * (c.y + chunks.y * c.z);
}

fn index4(p: vec3<u32>) -> u32 {
    return p.x + 4u * p.y + 16u * p.z;
}

// Voxel \`i\` (0..64) of the voxel group starting at word \`ptr\`.
fn group_voxel(ptr: u32, i: u32) -> u32 {
    return (voxel_word(ptr + i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

// A material's entry (docs/FORMAT.md §5.4).
struct Material {
    kind: u32,
    albedo: vec3<f32>,
    emission: f32,
    roughness: f32,
}

fn material(id: u32) -> Material {
    let w0 = material_word(4u * id);
    let w1 = material_word(4u * id + 1u);
    let w2 = material_word(4u * id + 2u);
    let rg = unpack2x16float(w1);
    let be = unpack2x16float(w2);
    return Material(w0 & 3u, vec3<f32>(rg.x, rg.y, be.x), be.y, unpack2x16float(w0).y);
}

// Rays and the event model every traversal shares (world/src/traverse/ray.rs, in f32).
//
// A ray keeps its origin split into an integer part \`o_int\` and a fraction \`o_frac\` in [0, 1)
// (docs/NAADF.md §9), so precision does not depend on where in the world it starts.
// The direction \`d\` is kept exactly as given (not renormalised, which would move the line
// by an f32 rounding): times are in units of |d| and the ray's \`len\` converts them to
// distances. Every decision compares plane-crossing times from the one function \`t_at\`,
// so the traversal is a consistent walk of the event order "(t, axis), x before y before
// z at equal t"; it departs from the CPU's f64 order only where two crossings are within
// f32 rounding of each other.

// A cell bound beyond any world for unconstrained axes (the CPU walk uses 2^40, which no
// i32 holds).
const FAR_CELL: i32 = 1073741824;
const T_INF: f32 = 3.0e38;
const NO_AXIS: u32 = 3u;

struct Ray {
    o_int: vec3<i32>,
    o_frac: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    len: f32,
}

fn ray_new(o_int: vec3<i32>, o_frac: vec3<f32>, d: vec3<f32>) -> Ray {
    // The inverse of a zero component is never read: such axes never cross a plane.
    let safe = select(vec3<f32>(1.0), d, d != vec3<f32>(0.0));
    return Ray(o_int, o_frac, d, 1.0 / safe, length(d));
}

// A ray from an unsplit origin.
fn ray_from(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(o);
    return ray_new(vec3<i32>(fl), min(o - fl, vec3<f32>(0.99999994)), d);
}

// The ray's point at time \`t\`, relative to its integer origin.
fn ray_local(r: Ray, t: f32) -> vec3<f32> {
    return r.o_frac + r.d * t;
}

// A ray starting at \`p\` (relative to \`r\`'s integer origin) along \`d\`.
fn ray_at(r: Ray, p: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(p);
    return ray_new(r.o_int + vec3<i32>(fl), min(p - fl, vec3<f32>(0.99999994)), d);
}

// Time at which the ray crosses plane \`k\` of \`axis\`.
fn t_at(r: Ray, a: u32, k: i32) -> f32 {
    return (f32(k - r.o_int[a]) - r.o_frac[a]) * r.inv[a];
}

// Whether the crossing of plane \`k\` of axis \`b\` comes before the event \`(t, a)\`.
fn crossed(r: Ray, b: u32, k: i32, t: f32, a: u32) -> bool {
    let tb = t_at(r, b, k);
    return tb < t || (tb == t && b < a);
}

// The cell of axis \`b\` right after event \`(t, a)\`, known to lie in \`lo..=hi\`.
fn cell_after(r: Ray, b: u32, t: f32, a: u32, lo: i32, hi: i32) -> i32 {
    let d = r.d[b];
    if lo == hi || d == 0.0 {
        return lo;
    }
    let p = r.o_frac[b] + d * t;
    let fl = floor(p);
    var k = clamp(i32(fl) + r.o_int[b], lo, hi);
    let f = p - fl;
    // Far from a plane the floor is certain; near one, decide by crossing times.
    let tol = 4e-6 * (abs(d * t) + 1.0);
    if f > tol && f < 1.0 - tol {
        return k;
    }
    if d > 0.0 {
        while k < hi && crossed(r, b, k + 1, t, a) {
            k += 1;
        }
        while k > lo && !crossed(r, b, k, t, a) {
            k -= 1;
        }
    } else {
        while k > lo && crossed(r, b, k, t, a) {
            k -= 1;
        }
        while k < hi && !crossed(r, b, k + 1, t, a) {
            k += 1;
        }
    }
    return k;
}

// Where a ray begins inside the box [0, size): its first cell, the time it is entered and
// the axis whose plane it crossed (NO_AXIS when the origin is inside). \`ok\` is false when
// the ray misses the box.
struct Entry {
    cell: vec3<i32>,
    t: f32,
    axis: u32,
    ok: bool,
}

fn ray_entry(r: Ray, size: vec3<i32>) -> Entry {
    let start = r.o_int;
    var miss = Entry(vec3<i32>(0), 0.0, NO_AXIS, false);
    if all(start >= vec3<i32>(0)) && all(start < size) {
        return Entry(start, 0.0, NO_AXIS, true);
    }
    // The last slab-entry event, in (t, axis) order.
    var bt = 0.0;
    var ba = NO_AXIS;
    for (var a = 0u; a < 3u; a++) {
        var plane: i32;
        if start[a] < 0 {
            if r.d[a] <= 0.0 {
                return miss;
            }
            plane = 0;
        } else if start[a] >= size[a] {
            if r.d[a] >= 0.0 {
                return miss;
            }
            plane = size[a];
        } else {
            continue;
        }
        let t = t_at(r, a, plane);
        if ba == NO_AXIS || t >= bt {
            bt = t;
            ba = a;
        }
    }
    var cell = vec3<i32>(0);
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            cell[b] = select(size[b] - 1, 0, r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            cell[b] = cell_after(r, b, bt, ba, start[b], FAR_CELL);
        } else if r.d[b] < 0.0 {
            cell[b] = cell_after(r, b, bt, ba, -FAR_CELL, start[b]);
        } else {
            cell[b] = start[b];
        }
    }
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return miss;
    }
    return Entry(cell, bt, ba, true);
}

// When a ray inside the box [0, size] leaves it: the first crossing of a far plane it moves
// toward (world/src/traverse/ray.rs \`leave_time\`).
fn leave_time(r: Ray, size: vec3<i32>) -> f32 {
    var t = T_INF;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            t = min(t, t_at(r, a, select(0, size[a], r.d[a] > 0.0)));
        }
    }
    return t;
}

// Leaving the empty cuboid made of \`cell\` extended by \`skip\` cells toward the ray on each
// axis: the exit event and the cell entered by it.
struct Exit {
    t: f32,
    axis: u32,
    next: vec3<i32>,
}

fn ray_exit(r: Ray, cell: vec3<i32>, skip: vec3<i32>) -> Exit {
    var bound = vec3<i32>(0);
    var bt = T_INF;
    var ba = 0u;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] == 0.0 {
            continue;
        }
        bound[a] = select(cell[a] - skip[a], cell[a] + 1 + skip[a], r.d[a] > 0.0);
        let t = t_at(r, a, bound[a]);
        if t < bt {
            bt = t;
            ba = a;
        }
    }
    var next = cell;
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            next[b] = select(bound[b] - 1, bound[b], r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b], cell[b] + skip[b]);
        } else if r.d[b] < 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b] - skip[b], cell[b]);
        }
    }
    return Exit(bt, ba, next);
}

// Amanatides–Woo state in the same event order (ties step the lowest axis first).
struct Dda {
    cell: vec3<i32>,
    tmax: vec3<f32>,
    t: f32,
    axis: u32,
}

fn dda_start(r: Ray, e: Entry) -> Dda {
    var tmax = vec3<f32>(T_INF);
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            tmax[a] = t_at(r, a, select(e.cell[a], e.cell[a] + 1, r.d[a] > 0.0));
        }
    }
    return Dda(e.cell, tmax, e.t, e.axis);
}

fn dda_advance(r: Ray, s: ptr<function, Dda>) {
    var a = 0u;
    if (*s).tmax[1] < (*s).tmax[a] {
        a = 1u;
    }
    if (*s).tmax[2] < (*s).tmax[a] {
        a = 2u;
    }
    (*s).t = (*s).tmax[a];
    let c = (*s).cell[a] + select(-1, 1, r.d[a] > 0.0);
    (*s).cell[a] = c;
    (*s).axis = a;
    (*s).tmax[a] = t_at(r, a, select(c, c + 1, r.d[a] > 0.0));
}

// The first solid voxel along a ray (of the world, or of an entity: then voxel and normal
// are entity-local).
struct Hit {
    hit: bool,
    // The step budget ran out (counts as a miss).
    exhausted: bool,
    voxel: vec3<i32>,
    // Axis of the entry face (NO_AXIS: the origin was inside the voxel).
    axis: u32,
    // Entry-face normal (zero when the origin was inside).
    normal: vec3<i32>,
    // Time of entry, in units of the ray's |d|.
    t: f32,
    material: u32,
    steps: u32,
    // Entity id, or NO_ENTITY (generated in the prelude).
    entity: u32,
}

fn no_hit(steps: u32) -> Hit {
    return Hit(false, false, vec3<i32>(0), NO_AXIS, vec3<i32>(0), T_INF, 0u, steps, NO_ENTITY);
}

fn make_hit(r: Ray, cell: vec3<i32>, t: f32, axis: u32, material: u32, steps: u32) -> Hit {
    var n = vec3<i32>(0);
    if axis != NO_AXIS {
        n[axis] = select(1, -1, r.d[axis] > 0.0);
    }
    return Hit(true, false, cell, axis, n, t, material, steps, NO_ENTITY);
}

// One full trace: the world loop (traverse.wgsl or grid.wgsl) through the static world,
// then the instances whose world boxes the ray crosses before the world's hit or exit,
// found through their hierarchy (docs/NAADF.md §11): the GPU twin of
// world/src/traverse/entities.rs. Only the nearest entity hit (lowest id at equal times)
// survives, and only if it comes strictly before the world's hit or exit. Local instances
// (previews, markers: world/src/entity/local.rs) follow the world's records and carry the id
// NO_ENTITY, so their hits read as static geometry to everything that follows entity ids.

// How the world loop ended.
const END_HIT: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_EXHAUSTED: u32 = 3u;

struct WorldTrace {
    hit: Hit,
    end: u32,
    // When the ray entered the world, and when it hit or left it.
    t_entry: f32,
    t_end: f32,
}

// The end of a world loop whose step budget ran out at time \`t\` (entered at \`t_entry\`).
fn ran_out(t_entry: f32, t: f32) -> WorldTrace {
    var h = no_hit(world_info.max_steps);
    h.exhausted = true;
    return WorldTrace(h, END_EXHAUSTED, t_entry, t);
}

var<private> best_entity: Hit;
// The inverse rotation of \`best_entity\`'s instance.
var<private> best_rotation: vec4<f32>;
// Entity-grid cells visited (added to the step count of an entity hit).
var<private> entity_steps: u32;
// Whether the last \`trace\` returned an instance's hit (a local instance's has no entity id).
var<private> hit_instance: bool;

// Whether the world holds any instance. The host builds a pipeline for each value and
// picks the one that matches its world: a device that runs neighbouring rays in lock step
// may run code that no ray takes, and without instances none of the walk is compiled.
override HAS_INSTANCES: bool = true;

// How many instances the walk finds before it stops to test them.
const INSTANCE_BATCH: u32 = 8u;

// The walk's node stack and found instances, at module scope, so that an invocation holds
// (and zeroes) one of each rather than one for every trace inlined into it.
var<private> bvh_stack: array<u32, BVH_STACK>;
var<private> found_t: array<f32, INSTANCE_BATCH>;
var<private> found_slot: array<u32, INSTANCE_BATCH>;

// Walks the instance hierarchy (world/src/entity/bvh.rs: four-wide nodes of NODE_WORDS
// words, the children's f32 boxes axis by axis, then their references) and tests every
// instance whose box the ray is inside at some t in [t_lo, t_hi] (or up to the best entity
// hit so far). Boxes are padded and rounded outward, so the f32 test never rejects an
// instance the ray can hit. The walk gathers up to INSTANCE_BATCH instances, then tests them
// in the order the ray enters their boxes, stopping at a box that starts after the best hit,
// and goes on while nodes are left. Testing outside the walk's loop keeps that loop small,
// which is what costs on a device that runs neighbouring rays in lock step. With \`any_hit\`
// it returns at the first hit before \`t_hi\`.
fn find_instances(r: Ray, t_lo: f32, t_hi: f32, any_hit: bool) {
    // The world loop says whether its structure is traced with entities: the comparison
    // trees hold geometry only.
    if !TRACES_ENTITIES || !HAS_INSTANCES || world_info.instance_slots == 0u {
        return;
    }
    // 1/d, with ±FAR for axes the ray does not move along.
    let inv = select(1.0 / r.d, select(vec3<f32>(BVH_FAR), vec3<f32>(-BVH_FAR), r.d < vec3<f32>(0.0)), r.d == vec3<f32>(0.0));
    let o = vec3<f32>(r.o_int);
    bvh_stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        var far_limit = t_hi * 1.000001 + 1e-3;
        if best_entity.hit {
            far_limit = min(far_limit, best_entity.t * 1.000001 + 1e-3);
        }
        // A node adds at most four instances, so one is taken while four places are left.
        var found = 0u;
        while sp > 0u && found + 4u <= INSTANCE_BATCH {
            sp -= 1u;
            let base = bvh_stack[sp] * NODE_WORDS;
            // The four lanes at once, axis by axis.
            let tx0 = ((node_lanes(base) - o.x) - r.o_frac.x) * inv.x;
            let tx1 = ((node_lanes(base + 4u) - o.x) - r.o_frac.x) * inv.x;
            let ty0 = ((node_lanes(base + 8u) - o.y) - r.o_frac.y) * inv.y;
            let ty1 = ((node_lanes(base + 12u) - o.y) - r.o_frac.y) * inv.y;
            let tz0 = ((node_lanes(base + 16u) - o.z) - r.o_frac.z) * inv.z;
            let tz1 = ((node_lanes(base + 20u) - o.z) - r.o_frac.z) * inv.z;
            let near = max(vec4<f32>(t_lo - 1e-3), max(min(tx0, tx1), max(min(ty0, ty1), min(tz0, tz1))));
            let far = min(vec4<f32>(far_limit), min(max(tx0, tx1), min(max(ty0, ty1), max(tz0, tz1))));
            let child = vec4<u32>(hierarchy_word(base + 24u), hierarchy_word(base + 25u), hierarchy_word(base + 26u), hierarchy_word(base + 27u));
            let entered = !(near > far) & (child != vec4<u32>(BVH_NONE));
            // Each lane in turn: no loop, so that no lane's index is dynamic.
            if entered.x {
                keep_lane(child.x, near.x, &sp, &found);
            }
            if entered.y {
                keep_lane(child.y, near.y, &sp, &found);
            }
            if entered.z {
                keep_lane(child.z, near.z, &sp, &found);
            }
            if entered.w {
                keep_lane(child.w, near.w, &sp, &found);
            }
        }
        // Nearest box first, until one starts after the best hit (whose own box started no
        // later: the boxes are padded beyond the f32 test's rounding).
        for (var left = found; left > 0u; left--) {
            var k = 0u;
            for (var j = 1u; j < left; j++) {
                if found_t[j] < found_t[k] {
                    k = j;
                }
            }
            if best_entity.hit && found_t[k] > best_entity.t {
                break;
            }
            test_instance(r, found_slot[k] * RECORD_WORDS, t_lo);
            if any_hit && best_entity.hit && best_entity.t < t_hi {
                return;
            }
            found_t[k] = found_t[left - 1u];
            found_slot[k] = found_slot[left - 1u];
        }
    }
}

// Keeps a lane the ray enters at \`near\`: an instance among the found ones, or a node on the
// stack.
fn keep_lane(c: u32, near: f32, sp: ptr<function, u32>, found: ptr<function, u32>) {
    if (c & BVH_LEAF) != 0u {
        found_t[*found] = near;
        found_slot[*found] = c & ~BVH_LEAF;
        *found += 1u;
    } else if *sp < BVH_STACK {
        bvh_stack[*sp] = c;
        *sp += 1u;
    }
}

// Four lanes' planes of one axis, from word \`at\` of the hierarchy.
fn node_lanes(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4<u32>(hierarchy_word(at), hierarchy_word(at + 1u), hierarchy_word(at + 2u), hierarchy_word(at + 3u)));
}

// Decodes a smallest-three quaternion (world/src/entity/pack.rs).
fn decode_quat(w0: u32, w1: u32) -> vec4<f32> {
    let s = vec3<f32>(vec3<u32>(w0 & 0x3FFFu, (w0 >> 14u) & 0x3FFFu, (w0 >> 28u) | ((w1 & 0x3FFu) << 4u)));
    let small = (s - 8192.0) / 8192.0;
    let rest = sqrt(max(1.0 - dot(small, small), 0.0));
    let k = (w1 >> 10u) & 3u;
    if k == 0u {
        return vec4<f32>(rest, small.x, small.y, small.z);
    } else if k == 1u {
        return vec4<f32>(small.x, rest, small.y, small.z);
    } else if k == 2u {
        return vec4<f32>(small.x, small.y, rest, small.z);
    }
    return vec4<f32>(small, rest);
}

// Rotates \`v\` by the unit quaternion \`q = (x, y, z, w)\`.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// An instance record's position in 1/128 voxel (record words 0 and 1).
fn record_position(dx: u32, dy: u32) -> vec3<u32> {
    return vec3<u32>(dx & 0x1FFFFFu, (dx >> 21u) | (((dy >> 21u) & 0xFFu) << 11u), dy & 0x1FFFFFu);
}

// An instance record's entity id (record word 4).
fn record_id(e: u32) -> u32 {
    return e & 0x3FFFu;
}

// Tests the instance record at word \`at\` against the ray; keeps the nearest entity hit.
fn test_instance(r: Ray, at: u32, t_lo: f32) {
    let dx = instance_word(at);
    let dy = instance_word(at + 1u);
    let dz = instance_word(at + 2u);
    let dw = instance_word(at + 3u);
    let e = instance_word(at + 4u);
    let id = record_id(e);
    let size = vec3<u32>((e >> 14u) & 0x7Fu, (e >> 21u) & 0x7Fu, ((e >> 28u) & 0xFu) | (((dy >> 29u) & 7u) << 4u));
    let pos = record_position(dx, dy);
    var limit = T_INF;
    var equal_ok = false;
    if best_entity.hit {
        limit = best_entity.t;
        equal_ok = id < best_entity.entity;
    }
    // The entity lies within |size| of its local-origin corner: reject rays that pass
    // farther (with slack for f32), before transforming anything.
    let rel = vec3<f32>(r.o_int - vec3<i32>(pos >> vec3<u32>(7u))) + (r.o_frac - vec3<f32>(pos & vec3<u32>(127u)) / 128.0);
    let tc = -dot(rel, r.d) / (r.len * r.len);
    let radius = (length(vec3<f32>(size)) + 0.01) / r.len;
    let closest = rel + r.d * tc;
    if dot(closest, closest) > radius * radius * r.len * r.len || tc + radius < t_lo || tc - radius > limit {
        return;
    }
    let q = decode_quat(dz, dw & 0xFFFu);
    let local = ray_from(rotate(q, rel), rotate(q, r.d));
    let isize = vec3<i32>(size);
    let entry = ray_entry(local, isize);
    if !entry.ok {
        return;
    }
    let base = (dw >> 12u) * TYPE_ALIGN;
    var s = dda_start(local, entry);
    loop {
        entity_steps += 1u;
        if s.t > limit || (s.t == limit && !equal_ok) {
            return;
        }
        if s.t >= t_lo {
            let c = vec3<u32>(s.cell);
            let v = entity_type_word(base + c.x + size.x * (c.y + size.y * c.z));
            if (v & ENTITY_SOLID) != 0u {
                var h = make_hit(local, s.cell, s.t, s.axis, v & MAX_MATERIAL, 0u);
                h.entity = id;
                best_entity = h;
                best_rotation = q;
                return;
            }
        }
        dda_advance(local, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= isize) {
            return;
        }
    }
}

// The world-space normal of the hit the last \`trace\` returned (entity-local normals are
// rotated back to the world).
fn world_normal(h: Hit) -> vec3<f32> {
    let n = vec3<f32>(h.normal);
    if !hit_instance {
        return n;
    }
    return rotate(conjugate(best_rotation), n);
}

// Clears the entity state of the last trace and runs the world loop: how a trace starts.
fn world_first(r: Ray) -> WorldTrace {
    entity_steps = 0u;
    best_entity = no_hit(0u);
    hit_instance = false;
    return world_loop(r);
}

// Traces \`r\` through the world and its entities.
fn trace(r: Ray) -> Hit {
    let w = world_first(r);
    if w.end == END_MISSED || w.end == END_EXHAUSTED {
        return w.hit;
    }
    find_instances(r, w.t_entry, w.t_end, false);
    if best_entity.hit && best_entity.t < w.t_end {
        hit_instance = true;
        var h = best_entity;
        h.steps = w.hit.steps + entity_steps;
        return h;
    }
    var h = w.hit;
    h.steps += entity_steps;
    return h;
}

// Whether \`trace(r)\` would hit (\`x\`) and whether it would run out of steps (\`y\`), for rays
// that only ask whether something is in the way (shadow rays): a ray that hits the world
// needs no instance walk, and one that leaves it stops walking at the first instance hit.
fn occlusion(r: Ray) -> vec2<bool> {
    let w = world_first(r);
    if w.end != END_LEFT {
        return vec2<bool>(w.hit.hit, w.hit.exhausted);
    }
    find_instances(r, w.t_entry, w.t_end, true);
    return vec2<bool>(best_entity.hit && best_entity.t < w.t_end, false);
}

// The world loop over the chunk → block → voxel hierarchy (docs/NAADF.md §9), with
// AADF jumps (\`USE_AADF\`, the \`naadf\` method) or without (\`nodf\`): the GPU twin of
// world/src/traverse/hierarchy.rs. It sees the static world alone: entities are found
// afterwards, through their hierarchy (trace.wgsl).

override USE_AADF: bool = true;
// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;


fn to_edge(c: u32, neg: bool, edge: u32) -> i32 {
    let m = c & (edge - 1u);
    return i32(select(edge - 1u - m, m, neg));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing = vec3<u32>(0u, 2u, 4u) + select(vec3<u32>(0u), vec3<u32>(1u), r.d > vec3<f32>(0.0));
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(cell);
        let chunk = chunk_word(chunk_index(p >> vec3<u32>(4u), chunks));
        var skip = vec3<i32>(0);
        let cs = cell_state(chunk);
        if cs == STATE_FULL {
            return WorldTrace(make_hit(r, cell, t, axis, chunk & MAX_MATERIAL, steps), END_HIT, entry.t, t);
        } else if cs == STATE_EMPTY {
            for (var a = 0u; a < 3u; a++) {
                skip[a] = to_edge(p[a], neg[a], 16u);
                if USE_AADF {
                    skip[a] += 16 * i32(aadf_field(chunk, facing[a], CHUNK_FIELD_BITS));
                }
            }
        } else {
            let block = block_word((chunk & PAYLOAD) + index4((p >> vec3<u32>(2u)) & vec3<u32>(3u)));
            let bs = cell_state(block);
            if bs == STATE_FULL {
                return WorldTrace(make_hit(r, cell, t, axis, block & MAX_MATERIAL, steps), END_HIT, entry.t, t);
            } else if bs == STATE_EMPTY {
                for (var a = 0u; a < 3u; a++) {
                    skip[a] = to_edge(p[a], neg[a], 4u);
                    if USE_AADF {
                        skip[a] += 4 * i32(aadf_field(block, facing[a], CELL_FIELD_BITS));
                    }
                }
            } else {
                let v = group_voxel(block & PAYLOAD, index4(p & vec3<u32>(3u)));
                if (v & VOXEL_SOLID) != 0u {
                    return WorldTrace(make_hit(r, cell, t, axis, v & MAX_MATERIAL, steps), END_HIT, entry.t, t);
                }
                if USE_AADF {
                    for (var a = 0u; a < 3u; a++) {
                        skip[a] = i32(aadf_field(v, facing[a], CELL_FIELD_BITS));
                    }
                }
            }
        }
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            // An AADF box may reach beyond the world: the ray left it at the world's edge.
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, min(ex.t, leave_time(r, dims)));
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

// Pass \`roma_build\`: writes ROMA tiles (docs/RENDERING.md §3d), one workgroup per job.
// A job names a tile of one window; its 1024 column words are written from the world's
// cells of the window's level at the cells' centres, and the instances' boxes (found
// through the instance hierarchy), or cleared (a tile wholly outside the world). The GPU
// twin of \`tile_words\` and \`occupied\` in client/src/light/roma/.
//
// \`RomaWindow\`, \`RomaJob\` and the ROMA_* constants are generated by client/src/gpu/roma.rs.

@group(1) @binding(0) var<storage, read> roma_windows: array<RomaWindow>;
@group(1) @binding(1) var<storage, read> roma_jobs: array<RomaJob>;
@group(1) @binding(2) var<storage, read_write> roma_bits: array<u32>;

// Whether the world's cell of \`level\` holding world point \`p\` is not empty.
fn roma_occupied(level: u32, p: vec3<f32>) -> bool {
    let size = vec3<f32>(world_info.size);
    if any(p < vec3<f32>(0.0)) || any(p >= size) {
        return false;
    }
    let v = vec3<u32>(p);
    let c = chunk_word(chunk_index(v / 16u, world_info.chunks));
    let cs = cell_state(c);
    if cs == STATE_EMPTY {
        return false;
    }
    if cs == STATE_FULL || level >= 2u {
        return true;
    }
    let b = block_word((c & PAYLOAD) + index4((v / 4u) % 4u));
    let bs = cell_state(b);
    if level == 1u || bs != STATE_MIXED {
        return bs != STATE_EMPTY;
    }
    return (group_voxel(b & PAYLOAD, index4(v % 4u)) & VOXEL_SOLID) != 0u;
}

// Whether world point \`p\` lies in the box of an instance (the hierarchy's leaf boxes).
fn roma_in_instance(p: vec3<f32>) -> bool {
    if world_info.instance_slots == 0u {
        return false;
    }
    var stack: array<u32, BVH_STACK>;
    stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        sp -= 1u;
        let base = stack[sp] * NODE_WORDS;
        for (var lane = 0u; lane < 4u; lane++) {
            let c = hierarchy_word(base + 24u + lane);
            if c == BVH_NONE {
                continue;
            }
            var inside = true;
            for (var a = 0u; a < 3u; a++) {
                let lo = bitcast<f32>(hierarchy_word(base + 8u * a + lane));
                let hi = bitcast<f32>(hierarchy_word(base + 8u * a + 4u + lane));
                inside = inside && p[a] >= lo && p[a] <= hi;
            }
            if !inside {
                continue;
            }
            if (c & BVH_LEAF) != 0u {
                return true;
            }
            if sp < BVH_STACK {
                stack[sp] = c;
                sp += 1u;
            }
        }
    }
    return false;
}

@compute @workgroup_size(64)
fn roma_build(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let j = wg.x + wg.y * groups.x;
    if j >= arrayLength(&roma_jobs) {
        return;
    }
    let job = roma_jobs[j];
    let w = roma_windows[job.window];
    let level = job.window % ROMA_LEVELS;
    let m = vec3<u32>(job.tile & vec3<i32>(i32(ROMA_WINDOW_TILES) - 1));
    let slot = m.x + ROMA_WINDOW_TILES * (m.y + ROMA_WINDOW_TILES * m.z);
    let first = (w.first_tile + slot) * ROMA_TILE_WORDS;
    for (var k = 0u; k < ROMA_TILE_WORDS / 64u; k++) {
        let col = lane + 64u * k;
        var word = 0u;
        if job.clear == 0u {
            let corner = job.tile * ROMA_TILE + vec3<i32>(i32(col % u32(ROMA_TILE)), i32(col / u32(ROMA_TILE)), 0);
            for (var z = 0; z < ROMA_TILE; z++) {
                let c = (vec3<f32>(corner + vec3<i32>(0, 0, z)) + 0.5) * w.cell;
                let p = w.t * c.x + w.b * c.y + w.w * c.z;
                if roma_occupied(level, p) || roma_in_instance(p) {
                    word |= 1u << u32(z);
                }
            }
        }
        roma_bits[first + col] = word;
    }
}

const ROMA_LEVELS: u32 = 3u;
const ROMA_TILE: i32 = 32i;
const ROMA_TILE_SHIFT: u32 = 5u;
const ROMA_TILE_WORDS: u32 = 1024u;
const ROMA_WINDOW_TILES: u32 = 8u;
const ROMA_REACH: f32 = 94.0f;
const ROMA_MAX_COLUMNS: u32 = 1024u;
const ROMA_FAR: f32 = 1e30f;
struct RomaInfo {
    // The camera the windows are centred on, in voxels.
    camera: vec3<f32>,
    // How far ambient occlusion looks, in voxels.
    ao_range: f32,
    // Candidate directions per axis of the concentric square.
    side: u32,
    // Candidate directions (\`side²\`); the sun's map follows them.
    directions: u32,
    // Padding to 16 bytes.
    _pad0: u32,
    // Padding to 16 bytes.
    _pad1: u32,
}
struct RomaWindow {
    // The frame's first row.
    t: vec3<f32>,
    // The level's cell edge, in voxels.
    cell: f32,
    // The frame's second row.
    b: vec3<f32>,
    // The window's first tile in \`roma_bits\` (in tiles).
    first_tile: u32,
    // The frame's third row: the map's direction.
    w: vec3<f32>,
    // How far off a surface a ray starts, in cells of this level.
    offset: f32,
    // The window's lowest tile, per map axis.
    base: vec3<i32>,
    // Padding to 16 bytes.
    _pad: u32,
}
struct RomaJob {
    // The tile's coordinates in its map, in tiles.
    tile: vec3<i32>,
    // Its window (\`map · ROMA_LEVELS + level\`).
    window: u32,
    // 1: the tile lies outside the world, so it is cleared without sampling.
    clear: u32,
    // Padding to 16 bytes.
    _pad0: u32,
    // Padding to 16 bytes.
    _pad1: u32,
    // Padding to 16 bytes.
    _pad2: u32,
}
`,fl=class{device;label;frame;sums;staging;key=``;samples=0;constructor(e,t){this.device=e,this.label=t,this.frame=e.createBuffer({size:tc.size,usage:GPUBufferUsage.UNIFORM|GPUBufferUsage.COPY_DST})}next(e,t,n,r){let i=n*r*16,a=hc(t,n,r,e);a===this.key&&this.sums||(this.sums?.destroy(),this.staging?.destroy(),this.sums=this.device.createBuffer({label:`${this.label} sums`,size:i,usage:GPUBufferUsage.STORAGE|GPUBufferUsage.COPY_SRC}),this.staging=this.device.createBuffer({label:`${this.label} frame`,size:i,usage:GPUBufferUsage.MAP_READ|GPUBufferUsage.COPY_DST}),this.key=a,this.samples=0);let o=Io(t,n,r);return this.device.queue.writeBuffer(this.frame,0,gc(tc,{cam_int:o.int,width:n,cam_frac:o.frac,height:r,forward:o.forward,seed:0,right:o.right,sample:this.samples,up:o.up,history:0})),this.sums}async finish(e,t,n){return this.samples+=1,il(new Float32Array(await wc(this.device,e,this.sums,0,this.staging,t*n*16)),t,n,1,!0)}},pl=(J.DIRECTIONS+1)*J.LEVELS,ml=J.WINDOW_TILES**3,hl=J.TILE_WORDS*4;function gl(e,t){let n=J.FRAMES[e];return[n[3*t],n[3*t+1],n[3*t+2]]}var _l=(e,t)=>e[0]*t[0]+e[1]*t[1]+e[2]*t[2];function vl(e,t){return[_l(gl(e,0),t),_l(gl(e,1),t),_l(gl(e,2),t)]}function yl(e,t,n){return vl(e,n).map(e=>e/J.CELL[t]).map(e=>Math.floor(e/J.TILE)-J.WINDOW_TILES/2)}function bl(e,t,n,r){let i=[1/0,1/0,1/0],a=[-1/0,-1/0,-1/0];for(let t=0;t<8;t++){let o=vl(e,[t&1?r[0]:n[0],t&2?r[1]:n[1],t&4?r[2]:n[2]]);for(let e=0;e<3;e++)i[e]=Math.min(i[e],o[e]),a[e]=Math.max(a[e],o[e])}let o=J.CELL[t]*J.TILE;return[i.map(e=>Math.floor(e/o)),a.map(e=>Math.floor(e/o))]}var xl=(e,t,n)=>e.every((e,r)=>e>=t[r]&&e<=n[r]),Sl=class{device;world;sample;sampleLayout;build;buildLayout;light;info;windows;bits;bases=Array(pl).fill(null);generation=-1;size=``;sums;constructor(e,t){this.device=e,this.world=t,{pipeline:this.sample,layout:this.sampleLayout}=bc(e,t,`roma.wgsl`,ul,`path_trace`,[`uniform`,`uniform`,`storage`,`uniform`,`read-only-storage`,`read-only-storage`]),{pipeline:this.build,layout:this.buildLayout}=bc(e,t,`roma_build.wgsl`,dl,`roma_build`,[`read-only-storage`,`read-only-storage`,`storage`]);let n=t=>e.createBuffer({size:t,usage:GPUBufferUsage.UNIFORM|GPUBufferUsage.COPY_DST});this.light=n(lc.length*4),e.queue.writeBuffer(this.light,0,new Uint32Array(lc)),this.info=n(ic.size),this.windows=e.createBuffer({label:`roma windows`,size:pl*ac.size,usage:GPUBufferUsage.STORAGE|GPUBufferUsage.COPY_DST}),this.bits=e.createBuffer({label:`roma maps`,size:pl*ml*hl,usage:GPUBufferUsage.STORAGE}),this.sums=new fl(e,`roma`)}async update(e,t){let n=JSON.stringify(e.chunks),r=this.generation<0||n!==this.size?`everything`:e.changesSince(this.generation),i=r===`everything`,a=new Map,o=(e,t)=>a.set(`${e}:${t}`,{tile:t,window:e}),s=new Uint8Array(pl*ac.size),c=J.WINDOW_TILES;for(let e=0;e<pl;e++){let[n,r]=[Math.floor(e/J.LEVELS),e%J.LEVELS],a=yl(n,r,t.pos),l=i?null:this.bases[e];if(!l||l.some((e,t)=>e!==a[t]))for(let t=0;t<c*c*c;t++){let n=[a[0]+t%c,a[1]+Math.floor(t/c)%c,a[2]+Math.floor(t/(c*c))];l&&n.every((e,t)=>e-l[t]>=0&&e-l[t]<c)||o(e,n)}this.bases[e]=a;let u=gc(ac,{t:gl(n,0),cell:J.CELL[r],b:gl(n,1),first_tile:e*ml,w:gl(n,2),offset:J.OFFSET[r],base:a});s.set(new Uint8Array(u),e*ac.size)}if(!i){let[t,n]=e.chunks;for(let e of r){let r=[e%t*16,Math.floor(e/t)%n*16,Math.floor(e/(t*n))*16],i=[r[0]+16,r[1]+16,r[2]+16];for(let e=0;e<pl;e++){let[t,n]=bl(Math.floor(e/J.LEVELS),e%J.LEVELS,r,i),a=this.bases[e],s=t.map((e,t)=>Math.max(e,a[t])),l=n.map((e,t)=>Math.min(e,a[t]+c-1));for(let t=s[2];t<=l[2];t++)for(let n=s[1];n<=l[1];n++)for(let r=s[0];r<=l[0];r++)o(e,[r,n,t])}}}if(this.generation=e.generation,this.size=n,this.device.queue.writeBuffer(this.windows,0,s),a.size===0)return;let l=e.chunks.map(e=>e*16),u=Array.from({length:pl},(e,t)=>bl(Math.floor(t/J.LEVELS),t%J.LEVELS,[0,0,0],l)),d=new Uint8Array(a.size*oc.size),f=0;for(let{tile:e,window:t}of a.values()){let[n,r]=u[t];d.set(new Uint8Array(gc(oc,{tile:e,window:t,clear:+!xl(e,n,r)})),f*oc.size),f+=1}let p=this.device.createBuffer({label:`roma jobs`,size:d.byteLength,usage:GPUBufferUsage.STORAGE|GPUBufferUsage.COPY_DST});this.device.queue.writeBuffer(p,0,d);let m=xc(this.device,this.buildLayout,[this.windows,p,this.bits]);await Sc(this.device,this.build(e.hasInstances),this.world.of(e),m,a.size),p.destroy()}get samples(){return this.sums.samples}async render(e,t,n,r){e.trackChanges(),await this.update(e,t);let i=this.sums.next(e,t,n,r);this.device.queue.writeBuffer(this.info,0,gc(ic,{camera:t.pos,ao_range:J.AO_RANGE,side:J.SIDE,directions:J.DIRECTIONS}));let a=xc(this.device,this.sampleLayout,[this.sums.frame,this.light,i,this.info,this.windows,this.bits]),o=await Cc(this.device,this.sample(e.hasInstances),this.world.of(e),a,n,r);return this.sums.finish(o,n,r)}},Cl=`// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the
// Rust code, the world's storage bindings.
struct WorldInfo {
    // World size in voxels.
    size: vec3<u32>,
    // Slots of the instance buffer on the device, the world's and then the local
    // instances' (records of 5 words; 0: no instance to trace).
    instance_slots: u32,
    // World size in chunks.
    chunks: vec3<u32>,
    // Cells a ray may visit before it counts as a miss.
    max_steps: u32,
}
@group(0) @binding(0) var<uniform> world_info: WorldInfo;
struct FrameInfo {
    // Camera position, integer part (floor).
    cam_int: vec3<i32>,
    // Image width in pixels.
    width: u32,
    // Camera position, fractional part in [0, 1).
    cam_frac: vec3<f32>,
    // Image height in pixels.
    height: u32,
    // View direction.
    forward: vec3<f32>,
    // The run's seed.
    seed: u32,
    // Image right, scaled by a·W/H.
    right: vec3<f32>,
    // Number of the sample this dispatch adds.
    sample: u32,
    // Image up, scaled by a.
    up: vec3<f32>,
    // 1 when a temporal pass has a history to blend with (0 for the path tracer).
    history: u32,
}
struct LightInfo {
    // Uniform sky: its radiance. Physical sky: the irradiance of the sun lighting it.
    sky: vec3<f32>,
    // 1 for the physical sky.
    sky_physical: u32,
    // Unit vector toward the sun (the sun lighting the physical sky when it is off).
    sun_dir: vec3<f32>,
    // 1 when the sun shines (its disc and its samples).
    sun_on: u32,
    // The disc's radiance.
    sun_disc: f32,
    // The weight of one disc sample: radiance times solid angle.
    sun_weight: f32,
    // 1 − cos of the disc's angular radius.
    sun_omc: f32,
    // Scattered rays after the camera ray.
    bounces: u32,
}
struct GiInfo {
    // Frames rendered in this history before this one.
    frame: u32,
    // The long-term TAA slot this frame writes (\`frame % TAA_SLOTS\`).
    taa_slot: u32,
    // Earlier frames the TAA may read (at most \`TAA_SLOTS − 1\`).
    taa_valid: u32,
    // The first frame rendered after the newest change of the materials, or of more
    // chunks than are marked one by one (0: none): the near-change rule everywhere.
    edit_frame: u32,
    // The first frame rendered after the newest change of any chunk, entity moves
    // included (0: none): the still path keeps no sample from before it.
    change_frame: u32,
    // This frame's jitter in the pixel, x (a point of a 32-point (0, 5, 2)-net).
    jitter_x: f32,
    // This frame's jitter in the pixel, y.
    jitter_y: f32,
    // 8×8 regions across.
    regions_x: u32,
    // 8×8 regions down.
    regions_y: u32,
    // Samples the sample ring holds.
    ring_capacity: u32,
    // 1 when the bilateral denoiser runs.
    denoise: u32,
    // Where each pixel's own secondary sample starts in \`mem\` (tagged with the
    // frame that traced it).
    off_own: u32,
    // Where the atmosphere table starts in \`mem\` (vec4 words; the cameras start at 0).
    off_lut: u32,
    // Where the first-hit surfaces start in \`mem\`.
    off_gbuf: u32,
    // Where the first-hit materials start in \`mem\`.
    off_gmat: u32,
    // Where the first-hit light starts in \`mem\`.
    off_emitted: u32,
    // Where the TAA's per-pixel sums and ranges start in \`mem\`.
    off_taa_info: u32,
    // Where the incoming light starts in \`mem\`.
    off_illum: u32,
    // Where the denoiser's intermediate starts in \`mem\`.
    off_illum2: u32,
    // Where the results start in \`mem\`.
    off_result: u32,
    // Where the refined samples start in \`mem\`.
    off_refined: u32,
    // Where the regions' statistics start in \`mem\`.
    off_region_info: u32,
    // Where the sample ring starts in \`mem\`.
    off_ring: u32,
    // Where the queued pixels start in \`words\`.
    off_queue_list: u32,
}
const STATE_SHIFT: u32 = 30u;
const STATE_EMPTY: u32 = 0u;
const STATE_FULL: u32 = 1u;
const STATE_MIXED: u32 = 2u;
const PAYLOAD: u32 = 1073741823u;
const MAX_MATERIAL: u32 = 32767u;
const VOXEL_SOLID: u32 = 32768u;
const CHUNK_FIELD_BITS: u32 = 5u;
const CELL_FIELD_BITS: u32 = 2u;
const KIND_DIFFUSE: u32 = 0u;
const KIND_EMISSIVE: u32 = 1u;
const KIND_METAL: u32 = 2u;
const KIND_MIRROR: u32 = 3u;
const ENTITY_SOLID: u32 = 2147483648u;
const TYPE_ALIGN: u32 = 64u;
const RECORD_WORDS: u32 = 5u;
const NO_ENTITY: u32 = 16383u;
const NODE_WORDS: u32 = 28u;
const BVH_STACK: u32 = 64u;
const BVH_LEAF: u32 = 2147483648u;
const BVH_NONE: u32 = 4294967295u;
const BVH_FAR: f32 = 1e30f;
const SURFACE_OFFSET: f32 = 0.01f;
const MIN_ALPHA: f32 = 0.001f;
const PI: f32 = 3.1415927f;
const PLANET_RADIUS: f32 = 6360000.0f;
const ATMOSPHERE_HEIGHT: f32 = 60000.0f;
const EYE_HEIGHT: f32 = 100.0f;
const VIEW_STEPS: u32 = 24u;
const LIGHT_STEPS: u32 = 6u;
const RAYLEIGH: vec3<f32> = vec3<f32>(5.802e-6f, 1.3558e-5f, 3.31e-5f);
const RAYLEIGH_SCALE: f32 = 8000.0f;
const MIE_SCATTER: f32 = 3.996e-6f;
const MIE_EXTINCTION: f32 = 4.44e-6f;
const MIE_SCALE: f32 = 1200.0f;
const MIE_G: f32 = 0.8f;
const OZONE: vec3<f32> = vec3<f32>(6.5e-7f, 1.881e-6f, 8.5e-8f);
const OZONE_CENTRE: f32 = 25000.0f;
const OZONE_HALF_WIDTH: f32 = 15000.0f;
// The first word of each buffer in \`world\`.
struct WorldOffsets {
    chunks: u32,
    blocks: u32,
    voxels: u32,
    materials: u32,
    entity_types: u32,
    entity_instances: u32,
    entity_hierarchy: u32,
    structure: u32,
}
@group(0) @binding(1) var<uniform> world_offsets: WorldOffsets;
@group(0) @binding(2) var<storage, read> world: array<u32>;
fn chunk_word(i: u32) -> u32 { return world[world_offsets.chunks + i]; }
fn block_word(i: u32) -> u32 { return world[world_offsets.blocks + i]; }
fn voxel_word(i: u32) -> u32 { return world[world_offsets.voxels + i]; }
fn material_word(i: u32) -> u32 { return world[world_offsets.materials + i]; }
fn entity_type_word(i: u32) -> u32 { return world[world_offsets.entity_types + i]; }
fn instance_word(i: u32) -> u32 { return world[world_offsets.entity_instances + i]; }
fn hierarchy_word(i: u32) -> u32 { return world[world_offsets.entity_hierarchy + i]; }
fn structure_word(i: u32) -> u32 { return world[world_offsets.structure + i]; }

// The world buffers (docs/FORMAT.md §5) and how to read their cells.
//
// Generated by naadf-client (client/src/gpu/shaders.rs) from the Rust definitions, in the
// prelude before this file:
// - the parameters \`world_info: WorldInfo\` (size in voxels and chunks, the instance
//   buffer's slots, the step budget);
// - the constants of the cell layout (STATE_*, PAYLOAD, MAX_MATERIAL, VOXEL_SOLID,
//   CHUNK_FIELD_BITS, CELL_FIELD_BITS), the material kinds (KIND_*), the entity layout
//   (ENTITY_SOLID, TYPE_ALIGN, RECORD_WORDS, NO_ENTITY), the instance hierarchy's (NODE_WORDS,
//   BVH_*) and the frame modes (MODE_*);
// - the storage bindings and the accessors \`chunk_word\`, \`block_word\`, \`voxel_word\`,
//   \`material_word\`, \`entity_type_word\`, \`instance_word\`, \`hierarchy_word\` (and
//   \`structure_word\` for the comparison traversals): a buffer larger than the adapter's
//   storage-binding limit is split across several bindings, and the accessor picks the
//   part.

// State of a chunk or block cell: STATE_EMPTY, STATE_FULL or (also for state 3)
// STATE_MIXED.
fn cell_state(c: u32) -> u32 {
    return min(c >> STATE_SHIFT, STATE_MIXED);
}

// Field \`dir\` (order −x, +x, −y, +y, −z, +z) of a packed AADF.
fn aadf_field(word: u32, dir: u32, bits: u32) -> u32 {
    return (word >> (bits * dir)) & ((1u << bits) - 1u);
}

// The index of chunk \`c\` in a world of \`chunks\` chunks (\`world_info.chunks\`). Loops read
// \`world_info\` once before they start and pass its fields: it is a storage buffer, and a
// storage read in every step is a bounds-checked load on lavapipe.
fn chunk_index(c: vec3<u32>, chunks: vec3<u32>) -> u32 {
    return c.x + chunks.x * (c.y + chunks.y * c.z);
}

fn index4(p: vec3<u32>) -> u32 {
    return p.x + 4u * p.y + 16u * p.z;
}

// Voxel \`i\` (0..64) of the voxel group starting at word \`ptr\`.
fn group_voxel(ptr: u32, i: u32) -> u32 {
    return (voxel_word(ptr + i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

// A material's entry (docs/FORMAT.md §5.4).
struct Material {
    kind: u32,
    albedo: vec3<f32>,
    emission: f32,
    roughness: f32,
}

fn material(id: u32) -> Material {
    let w0 = material_word(4u * id);
    let w1 = material_word(4u * id + 1u);
    let w2 = material_word(4u * id + 2u);
    let rg = unpack2x16float(w1);
    let be = unpack2x16float(w2);
    return Material(w0 & 3u, vec3<f32>(rg.x, rg.y, be.x), be.y, unpack2x16float(w0).y);
}

// Rays and the event model every traversal shares (world/src/traverse/ray.rs, in f32).
//
// A ray keeps its origin split into an integer part \`o_int\` and a fraction \`o_frac\` in [0, 1)
// (docs/NAADF.md §9), so precision does not depend on where in the world it starts.
// The direction \`d\` is kept exactly as given (not renormalised, which would move the line
// by an f32 rounding): times are in units of |d| and the ray's \`len\` converts them to
// distances. Every decision compares plane-crossing times from the one function \`t_at\`,
// so the traversal is a consistent walk of the event order "(t, axis), x before y before
// z at equal t"; it departs from the CPU's f64 order only where two crossings are within
// f32 rounding of each other.

// A cell bound beyond any world for unconstrained axes (the CPU walk uses 2^40, which no
// i32 holds).
const FAR_CELL: i32 = 1073741824;
const T_INF: f32 = 3.0e38;
const NO_AXIS: u32 = 3u;

struct Ray {
    o_int: vec3<i32>,
    o_frac: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    len: f32,
}

fn ray_new(o_int: vec3<i32>, o_frac: vec3<f32>, d: vec3<f32>) -> Ray {
    // The inverse of a zero component is never read: such axes never cross a plane.
    let safe = select(vec3<f32>(1.0), d, d != vec3<f32>(0.0));
    return Ray(o_int, o_frac, d, 1.0 / safe, length(d));
}

// A ray from an unsplit origin.
fn ray_from(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(o);
    return ray_new(vec3<i32>(fl), min(o - fl, vec3<f32>(0.99999994)), d);
}

// The ray's point at time \`t\`, relative to its integer origin.
fn ray_local(r: Ray, t: f32) -> vec3<f32> {
    return r.o_frac + r.d * t;
}

// A ray starting at \`p\` (relative to \`r\`'s integer origin) along \`d\`.
fn ray_at(r: Ray, p: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(p);
    return ray_new(r.o_int + vec3<i32>(fl), min(p - fl, vec3<f32>(0.99999994)), d);
}

// Time at which the ray crosses plane \`k\` of \`axis\`.
fn t_at(r: Ray, a: u32, k: i32) -> f32 {
    return (f32(k - r.o_int[a]) - r.o_frac[a]) * r.inv[a];
}

// Whether the crossing of plane \`k\` of axis \`b\` comes before the event \`(t, a)\`.
fn crossed(r: Ray, b: u32, k: i32, t: f32, a: u32) -> bool {
    let tb = t_at(r, b, k);
    return tb < t || (tb == t && b < a);
}

// The cell of axis \`b\` right after event \`(t, a)\`, known to lie in \`lo..=hi\`.
fn cell_after(r: Ray, b: u32, t: f32, a: u32, lo: i32, hi: i32) -> i32 {
    let d = r.d[b];
    if lo == hi || d == 0.0 {
        return lo;
    }
    let p = r.o_frac[b] + d * t;
    let fl = floor(p);
    var k = clamp(i32(fl) + r.o_int[b], lo, hi);
    let f = p - fl;
    // Far from a plane the floor is certain; near one, decide by crossing times.
    let tol = 4e-6 * (abs(d * t) + 1.0);
    if f > tol && f < 1.0 - tol {
        return k;
    }
    if d > 0.0 {
        while k < hi && crossed(r, b, k + 1, t, a) {
            k += 1;
        }
        while k > lo && !crossed(r, b, k, t, a) {
            k -= 1;
        }
    } else {
        while k > lo && crossed(r, b, k, t, a) {
            k -= 1;
        }
        while k < hi && !crossed(r, b, k + 1, t, a) {
            k += 1;
        }
    }
    return k;
}

// Where a ray begins inside the box [0, size): its first cell, the time it is entered and
// the axis whose plane it crossed (NO_AXIS when the origin is inside). \`ok\` is false when
// the ray misses the box.
struct Entry {
    cell: vec3<i32>,
    t: f32,
    axis: u32,
    ok: bool,
}

fn ray_entry(r: Ray, size: vec3<i32>) -> Entry {
    let start = r.o_int;
    var miss = Entry(vec3<i32>(0), 0.0, NO_AXIS, false);
    if all(start >= vec3<i32>(0)) && all(start < size) {
        return Entry(start, 0.0, NO_AXIS, true);
    }
    // The last slab-entry event, in (t, axis) order.
    var bt = 0.0;
    var ba = NO_AXIS;
    for (var a = 0u; a < 3u; a++) {
        var plane: i32;
        if start[a] < 0 {
            if r.d[a] <= 0.0 {
                return miss;
            }
            plane = 0;
        } else if start[a] >= size[a] {
            if r.d[a] >= 0.0 {
                return miss;
            }
            plane = size[a];
        } else {
            continue;
        }
        let t = t_at(r, a, plane);
        if ba == NO_AXIS || t >= bt {
            bt = t;
            ba = a;
        }
    }
    var cell = vec3<i32>(0);
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            cell[b] = select(size[b] - 1, 0, r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            cell[b] = cell_after(r, b, bt, ba, start[b], FAR_CELL);
        } else if r.d[b] < 0.0 {
            cell[b] = cell_after(r, b, bt, ba, -FAR_CELL, start[b]);
        } else {
            cell[b] = start[b];
        }
    }
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return miss;
    }
    return Entry(cell, bt, ba, true);
}

// When a ray inside the box [0, size] leaves it: the first crossing of a far plane it moves
// toward (world/src/traverse/ray.rs \`leave_time\`).
fn leave_time(r: Ray, size: vec3<i32>) -> f32 {
    var t = T_INF;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            t = min(t, t_at(r, a, select(0, size[a], r.d[a] > 0.0)));
        }
    }
    return t;
}

// Leaving the empty cuboid made of \`cell\` extended by \`skip\` cells toward the ray on each
// axis: the exit event and the cell entered by it.
struct Exit {
    t: f32,
    axis: u32,
    next: vec3<i32>,
}

fn ray_exit(r: Ray, cell: vec3<i32>, skip: vec3<i32>) -> Exit {
    var bound = vec3<i32>(0);
    var bt = T_INF;
    var ba = 0u;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] == 0.0 {
            continue;
        }
        bound[a] = select(cell[a] - skip[a], cell[a] + 1 + skip[a], r.d[a] > 0.0);
        let t = t_at(r, a, bound[a]);
        if t < bt {
            bt = t;
            ba = a;
        }
    }
    var next = cell;
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            next[b] = select(bound[b] - 1, bound[b], r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b], cell[b] + skip[b]);
        } else if r.d[b] < 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b] - skip[b], cell[b]);
        }
    }
    return Exit(bt, ba, next);
}

// Amanatides–Woo state in the same event order (ties step the lowest axis first).
struct Dda {
    cell: vec3<i32>,
    tmax: vec3<f32>,
    t: f32,
    axis: u32,
}

fn dda_start(r: Ray, e: Entry) -> Dda {
    var tmax = vec3<f32>(T_INF);
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            tmax[a] = t_at(r, a, select(e.cell[a], e.cell[a] + 1, r.d[a] > 0.0));
        }
    }
    return Dda(e.cell, tmax, e.t, e.axis);
}

fn dda_advance(r: Ray, s: ptr<function, Dda>) {
    var a = 0u;
    if (*s).tmax[1] < (*s).tmax[a] {
        a = 1u;
    }
    if (*s).tmax[2] < (*s).tmax[a] {
        a = 2u;
    }
    (*s).t = (*s).tmax[a];
    let c = (*s).cell[a] + select(-1, 1, r.d[a] > 0.0);
    (*s).cell[a] = c;
    (*s).axis = a;
    (*s).tmax[a] = t_at(r, a, select(c, c + 1, r.d[a] > 0.0));
}

// The first solid voxel along a ray (of the world, or of an entity: then voxel and normal
// are entity-local).
struct Hit {
    hit: bool,
    // The step budget ran out (counts as a miss).
    exhausted: bool,
    voxel: vec3<i32>,
    // Axis of the entry face (NO_AXIS: the origin was inside the voxel).
    axis: u32,
    // Entry-face normal (zero when the origin was inside).
    normal: vec3<i32>,
    // Time of entry, in units of the ray's |d|.
    t: f32,
    material: u32,
    steps: u32,
    // Entity id, or NO_ENTITY (generated in the prelude).
    entity: u32,
}

fn no_hit(steps: u32) -> Hit {
    return Hit(false, false, vec3<i32>(0), NO_AXIS, vec3<i32>(0), T_INF, 0u, steps, NO_ENTITY);
}

fn make_hit(r: Ray, cell: vec3<i32>, t: f32, axis: u32, material: u32, steps: u32) -> Hit {
    var n = vec3<i32>(0);
    if axis != NO_AXIS {
        n[axis] = select(1, -1, r.d[axis] > 0.0);
    }
    return Hit(true, false, cell, axis, n, t, material, steps, NO_ENTITY);
}

// One full trace: the world loop (traverse.wgsl or grid.wgsl) through the static world,
// then the instances whose world boxes the ray crosses before the world's hit or exit,
// found through their hierarchy (docs/NAADF.md §11): the GPU twin of
// world/src/traverse/entities.rs. Only the nearest entity hit (lowest id at equal times)
// survives, and only if it comes strictly before the world's hit or exit. Local instances
// (previews, markers: world/src/entity/local.rs) follow the world's records and carry the id
// NO_ENTITY, so their hits read as static geometry to everything that follows entity ids.

// How the world loop ended.
const END_HIT: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_EXHAUSTED: u32 = 3u;

struct WorldTrace {
    hit: Hit,
    end: u32,
    // When the ray entered the world, and when it hit or left it.
    t_entry: f32,
    t_end: f32,
}

// The end of a world loop whose step budget ran out at time \`t\` (entered at \`t_entry\`).
fn ran_out(t_entry: f32, t: f32) -> WorldTrace {
    var h = no_hit(world_info.max_steps);
    h.exhausted = true;
    return WorldTrace(h, END_EXHAUSTED, t_entry, t);
}

var<private> best_entity: Hit;
// The inverse rotation of \`best_entity\`'s instance.
var<private> best_rotation: vec4<f32>;
// Entity-grid cells visited (added to the step count of an entity hit).
var<private> entity_steps: u32;
// Whether the last \`trace\` returned an instance's hit (a local instance's has no entity id).
var<private> hit_instance: bool;

// Whether the world holds any instance. The host builds a pipeline for each value and
// picks the one that matches its world: a device that runs neighbouring rays in lock step
// may run code that no ray takes, and without instances none of the walk is compiled.
override HAS_INSTANCES: bool = true;

// How many instances the walk finds before it stops to test them.
const INSTANCE_BATCH: u32 = 8u;

// The walk's node stack and found instances, at module scope, so that an invocation holds
// (and zeroes) one of each rather than one for every trace inlined into it.
var<private> bvh_stack: array<u32, BVH_STACK>;
var<private> found_t: array<f32, INSTANCE_BATCH>;
var<private> found_slot: array<u32, INSTANCE_BATCH>;

// Walks the instance hierarchy (world/src/entity/bvh.rs: four-wide nodes of NODE_WORDS
// words, the children's f32 boxes axis by axis, then their references) and tests every
// instance whose box the ray is inside at some t in [t_lo, t_hi] (or up to the best entity
// hit so far). Boxes are padded and rounded outward, so the f32 test never rejects an
// instance the ray can hit. The walk gathers up to INSTANCE_BATCH instances, then tests them
// in the order the ray enters their boxes, stopping at a box that starts after the best hit,
// and goes on while nodes are left. Testing outside the walk's loop keeps that loop small,
// which is what costs on a device that runs neighbouring rays in lock step. With \`any_hit\`
// it returns at the first hit before \`t_hi\`.
fn find_instances(r: Ray, t_lo: f32, t_hi: f32, any_hit: bool) {
    // The world loop says whether its structure is traced with entities: the comparison
    // trees hold geometry only.
    if !TRACES_ENTITIES || !HAS_INSTANCES || world_info.instance_slots == 0u {
        return;
    }
    // 1/d, with ±FAR for axes the ray does not move along.
    let inv = select(1.0 / r.d, select(vec3<f32>(BVH_FAR), vec3<f32>(-BVH_FAR), r.d < vec3<f32>(0.0)), r.d == vec3<f32>(0.0));
    let o = vec3<f32>(r.o_int);
    bvh_stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        var far_limit = t_hi * 1.000001 + 1e-3;
        if best_entity.hit {
            far_limit = min(far_limit, best_entity.t * 1.000001 + 1e-3);
        }
        // A node adds at most four instances, so one is taken while four places are left.
        var found = 0u;
        while sp > 0u && found + 4u <= INSTANCE_BATCH {
            sp -= 1u;
            let base = bvh_stack[sp] * NODE_WORDS;
            // The four lanes at once, axis by axis.
            let tx0 = ((node_lanes(base) - o.x) - r.o_frac.x) * inv.x;
            let tx1 = ((node_lanes(base + 4u) - o.x) - r.o_frac.x) * inv.x;
            let ty0 = ((node_lanes(base + 8u) - o.y) - r.o_frac.y) * inv.y;
            let ty1 = ((node_lanes(base + 12u) - o.y) - r.o_frac.y) * inv.y;
            let tz0 = ((node_lanes(base + 16u) - o.z) - r.o_frac.z) * inv.z;
            let tz1 = ((node_lanes(base + 20u) - o.z) - r.o_frac.z) * inv.z;
            let near = max(vec4<f32>(t_lo - 1e-3), max(min(tx0, tx1), max(min(ty0, ty1), min(tz0, tz1))));
            let far = min(vec4<f32>(far_limit), min(max(tx0, tx1), min(max(ty0, ty1), max(tz0, tz1))));
            let child = vec4<u32>(hierarchy_word(base + 24u), hierarchy_word(base + 25u), hierarchy_word(base + 26u), hierarchy_word(base + 27u));
            let entered = !(near > far) & (child != vec4<u32>(BVH_NONE));
            // Each lane in turn: no loop, so that no lane's index is dynamic.
            if entered.x {
                keep_lane(child.x, near.x, &sp, &found);
            }
            if entered.y {
                keep_lane(child.y, near.y, &sp, &found);
            }
            if entered.z {
                keep_lane(child.z, near.z, &sp, &found);
            }
            if entered.w {
                keep_lane(child.w, near.w, &sp, &found);
            }
        }
        // Nearest box first, until one starts after the best hit (whose own box started no
        // later: the boxes are padded beyond the f32 test's rounding).
        for (var left = found; left > 0u; left--) {
            var k = 0u;
            for (var j = 1u; j < left; j++) {
                if found_t[j] < found_t[k] {
                    k = j;
                }
            }
            if best_entity.hit && found_t[k] > best_entity.t {
                break;
            }
            test_instance(r, found_slot[k] * RECORD_WORDS, t_lo);
            if any_hit && best_entity.hit && best_entity.t < t_hi {
                return;
            }
            found_t[k] = found_t[left - 1u];
            found_slot[k] = found_slot[left - 1u];
        }
    }
}

// Keeps a lane the ray enters at \`near\`: an instance among the found ones, or a node on the
// stack.
fn keep_lane(c: u32, near: f32, sp: ptr<function, u32>, found: ptr<function, u32>) {
    if (c & BVH_LEAF) != 0u {
        found_t[*found] = near;
        found_slot[*found] = c & ~BVH_LEAF;
        *found += 1u;
    } else if *sp < BVH_STACK {
        bvh_stack[*sp] = c;
        *sp += 1u;
    }
}

// Four lanes' planes of one axis, from word \`at\` of the hierarchy.
fn node_lanes(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4<u32>(hierarchy_word(at), hierarchy_word(at + 1u), hierarchy_word(at + 2u), hierarchy_word(at + 3u)));
}

// Decodes a smallest-three quaternion (world/src/entity/pack.rs).
fn decode_quat(w0: u32, w1: u32) -> vec4<f32> {
    let s = vec3<f32>(vec3<u32>(w0 & 0x3FFFu, (w0 >> 14u) & 0x3FFFu, (w0 >> 28u) | ((w1 & 0x3FFu) << 4u)));
    let small = (s - 8192.0) / 8192.0;
    let rest = sqrt(max(1.0 - dot(small, small), 0.0));
    let k = (w1 >> 10u) & 3u;
    if k == 0u {
        return vec4<f32>(rest, small.x, small.y, small.z);
    } else if k == 1u {
        return vec4<f32>(small.x, rest, small.y, small.z);
    } else if k == 2u {
        return vec4<f32>(small.x, small.y, rest, small.z);
    }
    return vec4<f32>(small, rest);
}

// Rotates \`v\` by the unit quaternion \`q = (x, y, z, w)\`.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// An instance record's position in 1/128 voxel (record words 0 and 1).
fn record_position(dx: u32, dy: u32) -> vec3<u32> {
    return vec3<u32>(dx & 0x1FFFFFu, (dx >> 21u) | (((dy >> 21u) & 0xFFu) << 11u), dy & 0x1FFFFFu);
}

// An instance record's entity id (record word 4).
fn record_id(e: u32) -> u32 {
    return e & 0x3FFFu;
}

// Tests the instance record at word \`at\` against the ray; keeps the nearest entity hit.
fn test_instance(r: Ray, at: u32, t_lo: f32) {
    let dx = instance_word(at);
    let dy = instance_word(at + 1u);
    let dz = instance_word(at + 2u);
    let dw = instance_word(at + 3u);
    let e = instance_word(at + 4u);
    let id = record_id(e);
    let size = vec3<u32>((e >> 14u) & 0x7Fu, (e >> 21u) & 0x7Fu, ((e >> 28u) & 0xFu) | (((dy >> 29u) & 7u) << 4u));
    let pos = record_position(dx, dy);
    var limit = T_INF;
    var equal_ok = false;
    if best_entity.hit {
        limit = best_entity.t;
        equal_ok = id < best_entity.entity;
    }
    // The entity lies within |size| of its local-origin corner: reject rays that pass
    // farther (with slack for f32), before transforming anything.
    let rel = vec3<f32>(r.o_int - vec3<i32>(pos >> vec3<u32>(7u))) + (r.o_frac - vec3<f32>(pos & vec3<u32>(127u)) / 128.0);
    let tc = -dot(rel, r.d) / (r.len * r.len);
    let radius = (length(vec3<f32>(size)) + 0.01) / r.len;
    let closest = rel + r.d * tc;
    if dot(closest, closest) > radius * radius * r.len * r.len || tc + radius < t_lo || tc - radius > limit {
        return;
    }
    let q = decode_quat(dz, dw & 0xFFFu);
    let local = ray_from(rotate(q, rel), rotate(q, r.d));
    let isize = vec3<i32>(size);
    let entry = ray_entry(local, isize);
    if !entry.ok {
        return;
    }
    let base = (dw >> 12u) * TYPE_ALIGN;
    var s = dda_start(local, entry);
    loop {
        entity_steps += 1u;
        if s.t > limit || (s.t == limit && !equal_ok) {
            return;
        }
        if s.t >= t_lo {
            let c = vec3<u32>(s.cell);
            let v = entity_type_word(base + c.x + size.x * (c.y + size.y * c.z));
            if (v & ENTITY_SOLID) != 0u {
                var h = make_hit(local, s.cell, s.t, s.axis, v & MAX_MATERIAL, 0u);
                h.entity = id;
                best_entity = h;
                best_rotation = q;
                return;
            }
        }
        dda_advance(local, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= isize) {
            return;
        }
    }
}

// The world-space normal of the hit the last \`trace\` returned (entity-local normals are
// rotated back to the world).
fn world_normal(h: Hit) -> vec3<f32> {
    let n = vec3<f32>(h.normal);
    if !hit_instance {
        return n;
    }
    return rotate(conjugate(best_rotation), n);
}

// Clears the entity state of the last trace and runs the world loop: how a trace starts.
fn world_first(r: Ray) -> WorldTrace {
    entity_steps = 0u;
    best_entity = no_hit(0u);
    hit_instance = false;
    return world_loop(r);
}

// Traces \`r\` through the world and its entities.
fn trace(r: Ray) -> Hit {
    let w = world_first(r);
    if w.end == END_MISSED || w.end == END_EXHAUSTED {
        return w.hit;
    }
    find_instances(r, w.t_entry, w.t_end, false);
    if best_entity.hit && best_entity.t < w.t_end {
        hit_instance = true;
        var h = best_entity;
        h.steps = w.hit.steps + entity_steps;
        return h;
    }
    var h = w.hit;
    h.steps += entity_steps;
    return h;
}

// Whether \`trace(r)\` would hit (\`x\`) and whether it would run out of steps (\`y\`), for rays
// that only ask whether something is in the way (shadow rays): a ray that hits the world
// needs no instance walk, and one that leaves it stops walking at the first instance hit.
fn occlusion(r: Ray) -> vec2<bool> {
    let w = world_first(r);
    if w.end != END_LEFT {
        return vec2<bool>(w.hit.hit, w.hit.exhausted);
    }
    find_instances(r, w.t_entry, w.t_end, true);
    return vec2<bool>(best_entity.hit && best_entity.t < w.t_end, false);
}

// The world loop over the chunk → block → voxel hierarchy (docs/NAADF.md §9), with
// AADF jumps (\`USE_AADF\`, the \`naadf\` method) or without (\`nodf\`): the GPU twin of
// world/src/traverse/hierarchy.rs. It sees the static world alone: entities are found
// afterwards, through their hierarchy (trace.wgsl).

override USE_AADF: bool = true;
// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;


fn to_edge(c: u32, neg: bool, edge: u32) -> i32 {
    let m = c & (edge - 1u);
    return i32(select(edge - 1u - m, m, neg));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing = vec3<u32>(0u, 2u, 4u) + select(vec3<u32>(0u), vec3<u32>(1u), r.d > vec3<f32>(0.0));
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(cell);
        let chunk = chunk_word(chunk_index(p >> vec3<u32>(4u), chunks));
        var skip = vec3<i32>(0);
        let cs = cell_state(chunk);
        if cs == STATE_FULL {
            return WorldTrace(make_hit(r, cell, t, axis, chunk & MAX_MATERIAL, steps), END_HIT, entry.t, t);
        } else if cs == STATE_EMPTY {
            for (var a = 0u; a < 3u; a++) {
                skip[a] = to_edge(p[a], neg[a], 16u);
                if USE_AADF {
                    skip[a] += 16 * i32(aadf_field(chunk, facing[a], CHUNK_FIELD_BITS));
                }
            }
        } else {
            let block = block_word((chunk & PAYLOAD) + index4((p >> vec3<u32>(2u)) & vec3<u32>(3u)));
            let bs = cell_state(block);
            if bs == STATE_FULL {
                return WorldTrace(make_hit(r, cell, t, axis, block & MAX_MATERIAL, steps), END_HIT, entry.t, t);
            } else if bs == STATE_EMPTY {
                for (var a = 0u; a < 3u; a++) {
                    skip[a] = to_edge(p[a], neg[a], 4u);
                    if USE_AADF {
                        skip[a] += 4 * i32(aadf_field(block, facing[a], CELL_FIELD_BITS));
                    }
                }
            } else {
                let v = group_voxel(block & PAYLOAD, index4(p & vec3<u32>(3u)));
                if (v & VOXEL_SOLID) != 0u {
                    return WorldTrace(make_hit(r, cell, t, axis, v & MAX_MATERIAL, steps), END_HIT, entry.t, t);
                }
                if USE_AADF {
                    for (var a = 0u; a < 3u; a++) {
                        skip[a] = i32(aadf_field(v, facing[a], CELL_FIELD_BITS));
                    }
                }
            }
        }
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            // An AADF box may reach beyond the world: the ray left it at the world's edge.
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, min(ex.t, leave_time(r, dims)));
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

// The samples of the lit passes: random streams (client/src/light/rng.rs), one per sample
// of each pixel, seeded from the run's seed, the pixel's index and the sample's number
// only; and the jittered camera ray of a sample.

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The stream of sample \`sample\` of pixel \`pixel\` under \`seed\`.
fn rng_new(seed: u32, pixel: u32, sample: u32) -> u32 {
    return pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(sample)));
}

// A uniform number in [0, 1) with 24 random bits.
fn rng_next(state: ptr<function, u32>) -> f32 {
    *state = pcg_hash(*state);
    return f32(*state >> 8u) * (1.0 / 16777216.0);
}

// The stream of sample \`sample\` of pixel \`pixel\`, after its first two draws: where in the
// pixel the sample's camera ray goes (uniform in [0, 1)²).
struct PixelStream {
    rng: u32,
    jitter: vec2<f32>,
}

fn pixel_stream(seed: u32, pixel: u32, sample: u32) -> PixelStream {
    var rng = rng_new(seed, pixel, sample);
    let jx = rng_next(&rng);
    let jy = rng_next(&rng);
    return PixelStream(rng, vec2<f32>(jx, jy));
}

// The camera's (unnormalised) direction through point \`jitter\` ([0, 1)²) of pixel \`gid\` of
// frame \`f\` (docs/CAMERA.md, with \`px + jitter.x\` for \`px + 0.5\`).
fn camera_dir(f: FrameInfo, gid: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let sx = 2.0 * (f32(gid.x) + jitter.x) / f32(f.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + jitter.y) / f32(f.height);
    return f.forward + sx * f.right + sy * f.up;
}

// The light model of the lit modes (docs/RENDERING.md §3a): the physical sky, the sun,
// BRDF sampling and one path's radiance. The GPU twin of client/src/light/ (sky.rs,
// scatter.rs, cpu.rs), written operation by operation like it so that the two path
// tracers agree up to rounding. Needs random.wgsl before it.
//
// The pass binds \`light: LightInfo\` (generated in the prelude from the Rust \`LightInfo\`),
// and declares \`DIFFUSE_TIER\` and \`diffuse_tier\` (no_tier.wgsl, or a lighting tier such as
// roma.wgsl) for \`path_step\`.

// PI, SURFACE_OFFSET (how far scattered and shadow rays start off the surface),
// MIN_ALPHA (the smallest GGX α a metal is traced with) and the physical sky's constants
// (PLANET_RADIUS, VIEW_STEPS, RAYLEIGH, MIE_G, OZONE, …) come from the prelude, generated
// from their Rust definitions in client/src/light/ (mod.rs, scatter.rs, sky.rs).

// ---- The physical sky (sky.rs) ----

// Distance from height \`h\` along zenith cosine \`mu\` to the sphere at height \`top\`; a
// negative value when it is not reached going forward.
fn sphere_distance(h: f32, mu: f32, top: f32) -> f32 {
    let r = PLANET_RADIUS + h;
    let disc = (top - h) * (2.0 * PLANET_RADIUS + top + h) + r * r * mu * mu;
    if disc < 0.0 {
        return -1.0;
    }
    let s = sqrt(disc);
    let far = -r * mu + s;
    if far < 0.0 {
        return -1.0;
    }
    let near = -r * mu - s;
    return select(far, near, near > 0.0);
}

struct Medium {
    sigma: vec3<f32>,
    rayleigh: f32,
    mie: f32,
}

fn medium(h: f32) -> Medium {
    let rayleigh = exp(-h / RAYLEIGH_SCALE);
    let mie = exp(-h / MIE_SCALE);
    let ozone = max(1.0 - abs(h - OZONE_CENTRE) / OZONE_HALF_WIDTH, 0.0);
    return Medium(RAYLEIGH * rayleigh + MIE_EXTINCTION * mie + OZONE * ozone, rayleigh, mie);
}

fn sun_transmittance(h: f32, mu: f32) -> vec3<f32> {
    if mu < 0.0 && sphere_distance(h, mu, 0.0) >= 0.0 {
        return vec3<f32>(0.0);
    }
    let length = max(sphere_distance(h, mu, ATMOSPHERE_HEIGHT), 0.0);
    let dt = length / f32(LIGHT_STEPS);
    let r = PLANET_RADIUS + h;
    var depth = vec3<f32>(0.0);
    for (var i = 0u; i < LIGHT_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let hi = sqrt(t * t + 2.0 * r * mu * t + r * r) - PLANET_RADIUS;
        depth += medium(hi).sigma * dt;
    }
    return exp(-depth);
}

// Sky radiance along unit \`dir\` for unit sun direction \`sun\`, per unit of irradiance.
fn sky_physical(dir: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let mu = dir.y;
    let nu = dot(dir, sun);
    let h0 = EYE_HEIGHT;
    let r0 = PLANET_RADIUS + h0;
    var length = sphere_distance(h0, mu, 0.0);
    if !(mu < 0.0 && length >= 0.0) {
        length = max(sphere_distance(h0, mu, ATMOSPHERE_HEIGHT), 0.0);
    }
    let dt = length / f32(VIEW_STEPS);
    let phase_r = 3.0 / (16.0 * PI) * (1.0 + nu * nu);
    let g2 = MIE_G * MIE_G;
    let phase_m = (1.0 - g2) / (4.0 * PI * pow(1.0 + g2 - 2.0 * MIE_G * nu, 1.5));
    var depth = vec3<f32>(0.0);
    var inscatter = vec3<f32>(0.0);
    for (var i = 0u; i < VIEW_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let r = sqrt(t * t + 2.0 * r0 * mu * t + r0 * r0);
        let h = r - PLANET_RADIUS;
        let mu_sun = (r0 * sun.y + t * nu) / r;
        let m = medium(h);
        let to_sun = sun_transmittance(h, mu_sun);
        let view = exp(-(depth + 0.5 * m.sigma * dt));
        let scatter = RAYLEIGH * m.rayleigh * phase_r + MIE_SCATTER * m.mie * phase_m;
        inscatter += view * to_sun * scatter * dt;
        depth += m.sigma * dt;
    }
    return inscatter;
}

// The sky along unit \`d\`, evaluated directly (no disc).
fn sky_direct(d: vec3<f32>) -> vec3<f32> {
    if light.sky_physical != 0u {
        return sky_physical(d, light.sun_dir) * light.sky;
    }
    return light.sky;
}

// The sky along unit \`d\`; with \`disc\`, the sun's disc too. \`sky_base(d)\` is the including
// pass's choice: \`sky_direct\` (the path tracer) or the atmosphere table (\`gi\`).
fn sky_radiance(d: vec3<f32>, disc: bool) -> vec3<f32> {
    var l = sky_base(d);
    if disc {
        l += sun_disc(d);
    }
    return l;
}

// The sun's disc along unit \`d\` (0 off the disc, or with the sun off).
fn sun_disc(d: vec3<f32>) -> vec3<f32> {
    if light.sun_on != 0u && 1.0 - dot(d, light.sun_dir) <= light.sun_omc {
        return vec3<f32>(light.sun_disc);
    }
    return vec3<f32>(0.0);
}

// ---- Scattering (scatter.rs) ----

struct Basis {
    t: vec3<f32>,
    b: vec3<f32>,
}

fn basis(n: vec3<f32>) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

fn sample_cosine(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let f = basis(n);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (r * cos(phi)) + f.b * (r * sin(phi)) + n * sqrt(max(1.0 - u.x, 0.0)));
}

fn sample_cone(axis: vec3<f32>, omc: f32, u: vec2<f32>) -> vec3<f32> {
    let f = basis(axis);
    let x = u.x * omc;
    let c = 1.0 - x;
    let s = sqrt(max(x * (2.0 - x), 0.0));
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (s * cos(phi)) + f.b * (s * sin(phi)) + axis * c);
}

fn schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let k = 1.0 - clamp(c, 0.0, 1.0);
    let k2 = k * k;
    return f0 + (vec3<f32>(1.0) - f0) * (k2 * k2 * k);
}

fn smith_lambda(alpha: f32, c: f32) -> f32 {
    let c2 = max(c * c, 1e-12);
    let tan2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (-1.0 + sqrt(1.0 + alpha * alpha * tan2));
}

fn ggx_d(alpha: f32, c: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = c * c * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

fn ggx(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, alpha: f32, f0: vec3<f32>) -> vec3<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if co <= 0.0 || ci <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = normalize(wo + wi);
    let g2 = 1.0 / (1.0 + smith_lambda(alpha, co) + smith_lambda(alpha, ci));
    return schlick(f0, dot(wo, h)) * (ggx_d(alpha, dot(n, h)) * g2 / (4.0 * co * ci));
}

struct Scattered {
    dir: vec3<f32>,
    weight: vec3<f32>,
}

fn ggx_sample(n: vec3<f32>, wo: vec3<f32>, alpha: f32, f0: vec3<f32>, u: vec2<f32>) -> Scattered {
    let f = basis(n);
    let v = vec3<f32>(dot(wo, f.t), dot(wo, f.b), dot(wo, n));
    let vh = normalize(vec3<f32>(alpha * v.x, alpha * v.y, v.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = t1 * p1 + t2 * p2 + vh * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    let m = normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    let lwi = m * (2.0 * dot(v, m)) - v;
    let wi = normalize(f.t * lwi.x + f.b * lwi.y + n * lwi.z);
    let lo = smith_lambda(alpha, v.z);
    let li = smith_lambda(alpha, lwi.z);
    return Scattered(wi, schlick(f0, dot(v, m)) * ((1.0 + lo) / (1.0 + lo + li)));
}

// ---- Paths (cpu.rs) ----

// Whether a shadow ray meets anything before leaving the world (a ray out of cells counts
// as blocked).
fn blocked(r: Ray, p: vec3<f32>, dir: vec3<f32>) -> bool {
    return any(occlusion(ray_at(r, p, dir)));
}

// One sample of the sun's disc seen from \`p\` (relative to \`r\`'s integer origin, just off a
// surface of normal \`n\`): its direction, and the irradiance it brings (\`E·cosθ\`-weighted)
// when it is above the surface and unblocked, else 0. Two random numbers are drawn
// whenever the sun is on (cpu.rs \`sun_sample\`).
struct SunSample {
    dir: vec3<f32>,
    irradiance: f32,
}

fn sun_sample(r: Ray, p: vec3<f32>, n: vec3<f32>, rng: ptr<function, u32>) -> SunSample {
    if light.sun_on == 0u {
        return SunSample(vec3<f32>(0.0), 0.0);
    }
    let u = vec2<f32>(rng_next(rng), rng_next(rng));
    let wi = sample_cone(light.sun_dir, light.sun_omc, u);
    let c = dot(n, wi);
    if c > 0.0 && !blocked(r, p, wi) {
        return SunSample(wi, c * light.sun_weight);
    }
    return SunSample(wi, 0.0);
}

// One step of a path: what it adds and whether it goes on.
struct PathState {
    r: Ray,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    sees_disc: bool,
    alive: bool,
    // The normal of the first surface met (zero until then).
    first_normal: vec3<f32>,
}

// Follows the path in \`s\` to its next surface: adds the light found there and, when
// \`scatter\`, picks the next ray (or ends the path). Returns the distance to the surface
// (−1 when the ray found none).
fn path_step(s: ptr<function, PathState>, scatter: bool, rng: ptr<function, u32>) -> f32 {
    let r = (*s).r;
    let h = trace(r);
    let d = r.d / r.len;
    (*s).alive = false;
    if h.exhausted {
        return -1.0;
    }
    if !h.hit {
        (*s).radiance += (*s).throughput * sky_radiance(d, (*s).sees_disc);
        return -1.0;
    }
    let distance = h.t * r.len;
    if h.axis == NO_AXIS {
        return distance;
    }
    // Before any other trace: world_normal reads the last trace's entity rotation.
    let n = world_normal(h);
    if all((*s).first_normal == vec3<f32>(0.0)) {
        (*s).first_normal = n;
    }
    let m = material(h.material);
    if m.kind == KIND_EMISSIVE {
        (*s).radiance += (*s).throughput * m.albedo * m.emission;
    }
    // A lighting tier (\`roma\`, \`irradiance\`) lights diffuse and emissive surfaces itself,
    // and the path ends there; mirrors and metals scatter on.
    if DIFFUSE_TIER && m.kind != KIND_MIRROR && m.kind != KIND_METAL {
        let surface = vec3<f32>(r.o_int) + ray_local(r, h.t);
        (*s).radiance += (*s).throughput * diffuse_tier(h, surface, n, m.albedo, rng);
        return distance;
    }
    if !scatter {
        return distance;
    }
    let p = ray_local(r, h.t) + n * SURFACE_OFFSET;
    var next: Scattered;
    if m.kind == KIND_MIRROR {
        (*s).sees_disc = true;
        next = Scattered(d - n * (2.0 * dot(d, n)), m.albedo);
    } else {
        let wo = -d;
        let alpha = max(m.roughness, MIN_ALPHA);
        let sun = sun_sample(r, p, n, rng);
        if sun.irradiance > 0.0 {
            var f = m.albedo / PI;
            if m.kind == KIND_METAL {
                f = ggx(n, wo, sun.dir, alpha, m.albedo);
            }
            (*s).radiance += (*s).throughput * f * sun.irradiance;
        }
        let u = vec2<f32>(rng_next(rng), rng_next(rng));
        (*s).sees_disc = false;
        if m.kind == KIND_METAL {
            next = ggx_sample(n, wo, alpha, m.albedo, u);
        } else {
            next = Scattered(sample_cosine(n, u), m.albedo);
        }
    }
    if dot(next.dir, n) > 0.0 {
        (*s).throughput *= next.weight;
        (*s).r = ray_at(r, p, next.dir);
        (*s).alive = true;
    }
    return distance;
}

// One path: the radiance it brought back, the distance from its origin to the first
// surface (−1 for the sky) and that surface's normal.
struct PathSample {
    radiance: vec3<f32>,
    distance: f32,
    normal: vec3<f32>,
}

// The radiance arriving along \`primary\` when the path may scatter \`bounces\` more times,
// drawing from \`rng\`. \`sees_disc\`: whether the ray sees the sun's disc (camera and mirror
// rays do; rays scattered by other surfaces get the sun by next-event estimation instead).
fn path_radiance(primary: Ray, bounces: u32, sees_disc: bool, rng: ptr<function, u32>) -> PathSample {
    var s = PathState(primary, vec3<f32>(0.0), vec3<f32>(1.0), sees_disc, true, vec3<f32>(0.0));
    let distance = path_step(&s, bounces > 0u, rng);
    for (var bounce = 1u; bounce <= bounces && s.alive; bounce++) {
        path_step(&s, bounce < bounces, rng);
    }
    return PathSample(s.radiance, distance, s.first_normal);
}

// The irradiance cache's table (\`irradiance\`; docs/RENDERING.md §3e), shared by its sample
// pass (irradiance.wgsl) and its update passes (irradiance_update.wgsl). The GPU twin of
// client/src/light/irradiance/, which states the rules.
//
// A slot is IRR_WORDS words: the key's two words (FaceKey::words; both non-zero, an empty
// slot's are zero), the stamp of the last frame that requested it, the count of samples
// its mean holds, the sums of those samples (RGB, f32 bits), and the samples ever drawn
// (the next sample's number). Keys are placed by linear probing from \`irr_stream(key) &
// mask\`, and only a whole clear removes them.
//
// The request list: IRR_COUNT (slots requested this frame), IRR_FRESH (those with no
// samples), IRR_TAKEN (samples taken), IRR_OCCUPIED (slots keyed, kept across frames),
// then from IRR_LIST the slots.
// IRR_* and \`IrradianceInfo\` are generated by client/src/gpu/irradiance.rs.

// The stream of the entry of \`key\`: its home slot and its samples' random streams.
fn irr_stream(key: vec2<u32>) -> u32 {
    return pcg_hash(key.x ^ pcg_hash(key.y));
}

// The irradiance cache as the diffuse tier of \`irradiance\` (docs/RENDERING.md §3e): the
// sample pass looks up (and keys) the entry of each diffuse world face it meets, requests
// it for the update pass, and lights the surface with the entry's mean; an entity surface,
// or a face whose entry has no samples yet, is lit by gathering. Included by the sample
// pass before light.wgsl's paths, with irradiance_table.wgsl.

@group(1) @binding(3) var<uniform> irr: IrradianceInfo;
@group(1) @binding(4) var<storage, read_write> irr_table: array<atomic<u32>>;
@group(1) @binding(5) var<storage, read_write> irr_requests: array<atomic<u32>>;

const DIFFUSE_TIER: bool = true;

// The key of the face of world voxel \`voxel\` with outward normal \`normal\` (FaceKey::words).
fn irr_key(voxel: vec3<i32>, normal: vec3<i32>) -> vec2<u32> {
    let v = vec3<u32>(voxel);
    var face = 4u + select(0u, 1u, normal.z < 0);
    if normal.x != 0 {
        face = select(0u, 1u, normal.x < 0);
    } else if normal.y != 0 {
        face = 2u + select(0u, 1u, normal.y < 0);
    }
    return vec2<u32>(v.x | 0x8000u | (v.z << 16u), 0x80000000u | (face << 16u) | v.y);
}

// Sets word \`at\` to \`value\` if it is zero; returns what it held before (zero: this
// invocation wrote it). The weak exchange may fail spuriously, finding zero: it is retried.
fn irr_claim(at: u32, value: u32) -> u32 {
    var r = atomicCompareExchangeWeak(&irr_table[at], 0u, value);
    while !r.exchanged && r.old_value == 0u {
        r = atomicCompareExchangeWeak(&irr_table[at], 0u, value);
    }
    return r.old_value;
}

// The slot of \`key\`, keyed there when absent; IRR_NONE when IRR_PROBES slots were taken.
// Each word is claimed once, so two invocations with one key agree on its slot, and a key
// is never held twice.
fn irr_find(key: vec2<u32>) -> u32 {
    var slot = irr_stream(key) & irr.mask;
    for (var i = 0u; i < IRR_PROBES; i++) {
        let at = slot * IRR_WORDS;
        var a = atomicLoad(&irr_table[at]);
        if a == 0u {
            a = irr_claim(at, key.x);
            if a == 0u {
                a = key.x;
            }
        }
        if a == key.x {
            var b = atomicLoad(&irr_table[at + 1u]);
            if b == 0u {
                b = irr_claim(at + 1u, key.y);
                if b == 0u {
                    b = key.y;
                    atomicAdd(&irr_requests[IRR_OCCUPIED], 1u);
                }
            }
            if b == key.y {
                return slot;
            }
        }
        slot = (slot + 1u) & irr.mask;
    }
    return IRR_NONE;
}

// Asks the update pass to refresh \`slot\` this frame (once, however many pixels see it).
fn irr_request(slot: u32) {
    let at = slot * IRR_WORDS;
    if atomicExchange(&irr_table[at + 2u], irr.stamp) == irr.stamp {
        return;
    }
    let i = atomicAdd(&irr_requests[IRR_COUNT], 1u);
    if i < irr.max_requests {
        atomicStore(&irr_requests[IRR_LIST + i], slot);
    }
    if atomicLoad(&irr_table[at + 3u]) == 0u {
        atomicAdd(&irr_requests[IRR_FRESH], 1u);
    }
}

// The mean irradiance of \`slot\` (RGB) and its sample count (w; 0: none yet).
fn irr_mean(slot: u32) -> vec4<f32> {
    let at = slot * IRR_WORDS;
    let count = atomicLoad(&irr_table[at + 3u]);
    if count == 0u {
        return vec4<f32>(0.0);
    }
    let sum = vec3<f32>(
        bitcast<f32>(atomicLoad(&irr_table[at + 4u])),
        bitcast<f32>(atomicLoad(&irr_table[at + 5u])),
        bitcast<f32>(atomicLoad(&irr_table[at + 6u])),
    );
    return vec4<f32>(sum / f32(count), f32(count));
}

// The irradiance at world point \`p\` (just off a surface of normal \`n\`) by gathering: one
// sun sample, and π times the radiance of one cosine ray: the sky's, or the emission of
// the surface it meets plus, for a diffuse world face with samples, albedo/π times its
// entry (a face met is keyed and requested, as a face seen is).
fn irr_gather(p: vec3<f32>, n: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    let base = ray_new(vec3<i32>(0), vec3<f32>(0.0), n);
    var e = vec3<f32>(sun_sample(base, p, n, rng).irradiance);
    let w = sample_cosine(n, vec2<f32>(rng_next(rng), rng_next(rng)));
    let h = trace(ray_at(base, p, w));
    if h.exhausted {
        return e;
    }
    if !h.hit {
        return e + PI * sky_radiance(w, false);
    }
    if h.axis == NO_AXIS {
        return e;
    }
    let m = material(h.material);
    var l = vec3<f32>(0.0);
    if m.kind == KIND_EMISSIVE {
        l += m.albedo * m.emission;
    }
    if h.entity == NO_ENTITY && m.kind != KIND_MIRROR && m.kind != KIND_METAL {
        // The face is near the view: it is keyed and requested too, so that the bounce
        // light of the next frames' gathers finds it.
        let slot = irr_find(irr_key(h.voxel, h.normal));
        if slot != IRR_NONE {
            irr_request(slot);
            l += m.albedo / PI * irr_mean(slot).xyz;
        }
    }
    return e + PI * l;
}

// The light of the diffuse surface of hit \`h\` at world point \`p\` with normal \`n\` (its
// emission excluded: the path adds it).
fn diffuse_tier(h: Hit, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    if h.entity == NO_ENTITY {
        let slot = irr_find(irr_key(h.voxel, h.normal));
        if slot != IRR_NONE {
            irr_request(slot);
            let e = irr_mean(slot);
            if e.w > 0.0 {
                return albedo / PI * e.xyz;
            }
        }
    }
    return albedo / PI * irr_gather(p + n * SURFACE_OFFSET, n, rng);
}

// Passes \`path_trace\` (progressive path tracing, \`pathtrace\`) and \`path_sample\` (one sample
// per pixel per frame, \`baseline\`), one invocation per pixel (docs/RENDERING.md §3a, §3b).
//
// \`path_trace\`: each dispatch adds sample number \`frame.sample\` to every pixel's running
// sum; the host divides by the count. A sample's random stream depends only on (seed, pixel, sample
// number), and every pixel adds its samples in number order, so the sums are the same bit
// for bit however the dispatches are grouped into submissions.
//
// One sample per dispatch, not a loop over samples: lavapipe (Mesa 22.3) miscompiles a
// sample loop around the bounce loop around the traversal loop, and pixels silently lose
// samples.
//
// \`FrameInfo\` and \`LightInfo\` are generated in the prelude from their Rust twins.

@group(1) @binding(0) var<uniform> frame: FrameInfo;
@group(1) @binding(1) var<uniform> light: LightInfo;
// \`path_trace\`: running sums (RGB, count). \`path_sample\`: this frame's sample (RGB, and
// the distance to the first surface, −1 for the sky).
@group(1) @binding(2) var<storage, read_write> radiance: array<vec4<f32>>;

// The path tracer sees the sky as the light model defines it, direction by direction.
fn sky_base(d: vec3<f32>) -> vec3<f32> {
    return sky_direct(d);
}

// Sample \`frame.sample\` of pixel \`gid\`.
fn pixel_sample(gid: vec2<u32>) -> PathSample {
    let stream = pixel_stream(frame.seed, gid.x + gid.y * frame.width, frame.sample);
    var rng = stream.rng;
    let r = ray_new(frame.cam_int, frame.cam_frac, camera_dir(frame, gid, stream.jitter));
    return path_radiance(r, light.bounces, true, &rng);
}

@compute @workgroup_size(8, 8)
fn path_trace(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let s = pixel_sample(gid.xy);
    radiance[gid.x + gid.y * frame.width] += vec4<f32>(s.radiance, 1.0);
}

@compute @workgroup_size(8, 8)
fn path_sample(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= frame.width || gid.y >= frame.height {
        return;
    }
    let s = pixel_sample(gid.xy);
    radiance[gid.x + gid.y * frame.width] = vec4<f32>(s.radiance, s.distance);
}

const IRR_WORDS: u32 = 8u;
const IRR_PROBES: u32 = 64u;
const IRR_NONE: u32 = 4294967295u;
const IRR_HISTORY: u32 = 64u;
const IRR_COUNT: u32 = 0u;
const IRR_FRESH: u32 = 1u;
const IRR_TAKEN: u32 = 2u;
const IRR_OCCUPIED: u32 = 3u;
const IRR_LIST: u32 = 4u;
const IRR_R2 = vec2<u32>(3242174889u, 2447445414u);
struct IrradianceInfo {
    // This frame's stamp (from 1): an entry requested this frame holds it.
    stamp: u32,
    // Slots of the table less one (a power of two less one).
    mask: u32,
    // Room in the request list, in slots.
    max_requests: u32,
    // Entry samples the frame's ray budget pays for.
    budget: u32,
    // Seed of the entries' sample streams.
    seed: u32,
    // Boxes in the invalidation list.
    boxes: u32,
    // Padding to 16 bytes.
    _pad0: u32,
    // Padding to 16 bytes.
    _pad1: u32,
}
`,wl=`// Generated by naadf-client (shaders.rs): the world parameters, the constants shared with the
// Rust code, the world's storage bindings.
struct WorldInfo {
    // World size in voxels.
    size: vec3<u32>,
    // Slots of the instance buffer on the device, the world's and then the local
    // instances' (records of 5 words; 0: no instance to trace).
    instance_slots: u32,
    // World size in chunks.
    chunks: vec3<u32>,
    // Cells a ray may visit before it counts as a miss.
    max_steps: u32,
}
@group(0) @binding(0) var<uniform> world_info: WorldInfo;
struct FrameInfo {
    // Camera position, integer part (floor).
    cam_int: vec3<i32>,
    // Image width in pixels.
    width: u32,
    // Camera position, fractional part in [0, 1).
    cam_frac: vec3<f32>,
    // Image height in pixels.
    height: u32,
    // View direction.
    forward: vec3<f32>,
    // The run's seed.
    seed: u32,
    // Image right, scaled by a·W/H.
    right: vec3<f32>,
    // Number of the sample this dispatch adds.
    sample: u32,
    // Image up, scaled by a.
    up: vec3<f32>,
    // 1 when a temporal pass has a history to blend with (0 for the path tracer).
    history: u32,
}
struct LightInfo {
    // Uniform sky: its radiance. Physical sky: the irradiance of the sun lighting it.
    sky: vec3<f32>,
    // 1 for the physical sky.
    sky_physical: u32,
    // Unit vector toward the sun (the sun lighting the physical sky when it is off).
    sun_dir: vec3<f32>,
    // 1 when the sun shines (its disc and its samples).
    sun_on: u32,
    // The disc's radiance.
    sun_disc: f32,
    // The weight of one disc sample: radiance times solid angle.
    sun_weight: f32,
    // 1 − cos of the disc's angular radius.
    sun_omc: f32,
    // Scattered rays after the camera ray.
    bounces: u32,
}
struct GiInfo {
    // Frames rendered in this history before this one.
    frame: u32,
    // The long-term TAA slot this frame writes (\`frame % TAA_SLOTS\`).
    taa_slot: u32,
    // Earlier frames the TAA may read (at most \`TAA_SLOTS − 1\`).
    taa_valid: u32,
    // The first frame rendered after the newest change of the materials, or of more
    // chunks than are marked one by one (0: none): the near-change rule everywhere.
    edit_frame: u32,
    // The first frame rendered after the newest change of any chunk, entity moves
    // included (0: none): the still path keeps no sample from before it.
    change_frame: u32,
    // This frame's jitter in the pixel, x (a point of a 32-point (0, 5, 2)-net).
    jitter_x: f32,
    // This frame's jitter in the pixel, y.
    jitter_y: f32,
    // 8×8 regions across.
    regions_x: u32,
    // 8×8 regions down.
    regions_y: u32,
    // Samples the sample ring holds.
    ring_capacity: u32,
    // 1 when the bilateral denoiser runs.
    denoise: u32,
    // Where each pixel's own secondary sample starts in \`mem\` (tagged with the
    // frame that traced it).
    off_own: u32,
    // Where the atmosphere table starts in \`mem\` (vec4 words; the cameras start at 0).
    off_lut: u32,
    // Where the first-hit surfaces start in \`mem\`.
    off_gbuf: u32,
    // Where the first-hit materials start in \`mem\`.
    off_gmat: u32,
    // Where the first-hit light starts in \`mem\`.
    off_emitted: u32,
    // Where the TAA's per-pixel sums and ranges start in \`mem\`.
    off_taa_info: u32,
    // Where the incoming light starts in \`mem\`.
    off_illum: u32,
    // Where the denoiser's intermediate starts in \`mem\`.
    off_illum2: u32,
    // Where the results start in \`mem\`.
    off_result: u32,
    // Where the refined samples start in \`mem\`.
    off_refined: u32,
    // Where the regions' statistics start in \`mem\`.
    off_region_info: u32,
    // Where the sample ring starts in \`mem\`.
    off_ring: u32,
    // Where the queued pixels start in \`words\`.
    off_queue_list: u32,
}
const STATE_SHIFT: u32 = 30u;
const STATE_EMPTY: u32 = 0u;
const STATE_FULL: u32 = 1u;
const STATE_MIXED: u32 = 2u;
const PAYLOAD: u32 = 1073741823u;
const MAX_MATERIAL: u32 = 32767u;
const VOXEL_SOLID: u32 = 32768u;
const CHUNK_FIELD_BITS: u32 = 5u;
const CELL_FIELD_BITS: u32 = 2u;
const KIND_DIFFUSE: u32 = 0u;
const KIND_EMISSIVE: u32 = 1u;
const KIND_METAL: u32 = 2u;
const KIND_MIRROR: u32 = 3u;
const ENTITY_SOLID: u32 = 2147483648u;
const TYPE_ALIGN: u32 = 64u;
const RECORD_WORDS: u32 = 5u;
const NO_ENTITY: u32 = 16383u;
const NODE_WORDS: u32 = 28u;
const BVH_STACK: u32 = 64u;
const BVH_LEAF: u32 = 2147483648u;
const BVH_NONE: u32 = 4294967295u;
const BVH_FAR: f32 = 1e30f;
const SURFACE_OFFSET: f32 = 0.01f;
const MIN_ALPHA: f32 = 0.001f;
const PI: f32 = 3.1415927f;
const PLANET_RADIUS: f32 = 6360000.0f;
const ATMOSPHERE_HEIGHT: f32 = 60000.0f;
const EYE_HEIGHT: f32 = 100.0f;
const VIEW_STEPS: u32 = 24u;
const LIGHT_STEPS: u32 = 6u;
const RAYLEIGH: vec3<f32> = vec3<f32>(5.802e-6f, 1.3558e-5f, 3.31e-5f);
const RAYLEIGH_SCALE: f32 = 8000.0f;
const MIE_SCATTER: f32 = 3.996e-6f;
const MIE_EXTINCTION: f32 = 4.44e-6f;
const MIE_SCALE: f32 = 1200.0f;
const MIE_G: f32 = 0.8f;
const OZONE: vec3<f32> = vec3<f32>(6.5e-7f, 1.881e-6f, 8.5e-8f);
const OZONE_CENTRE: f32 = 25000.0f;
const OZONE_HALF_WIDTH: f32 = 15000.0f;
// The first word of each buffer in \`world\`.
struct WorldOffsets {
    chunks: u32,
    blocks: u32,
    voxels: u32,
    materials: u32,
    entity_types: u32,
    entity_instances: u32,
    entity_hierarchy: u32,
    structure: u32,
}
@group(0) @binding(1) var<uniform> world_offsets: WorldOffsets;
@group(0) @binding(2) var<storage, read> world: array<u32>;
fn chunk_word(i: u32) -> u32 { return world[world_offsets.chunks + i]; }
fn block_word(i: u32) -> u32 { return world[world_offsets.blocks + i]; }
fn voxel_word(i: u32) -> u32 { return world[world_offsets.voxels + i]; }
fn material_word(i: u32) -> u32 { return world[world_offsets.materials + i]; }
fn entity_type_word(i: u32) -> u32 { return world[world_offsets.entity_types + i]; }
fn instance_word(i: u32) -> u32 { return world[world_offsets.entity_instances + i]; }
fn hierarchy_word(i: u32) -> u32 { return world[world_offsets.entity_hierarchy + i]; }
fn structure_word(i: u32) -> u32 { return world[world_offsets.structure + i]; }

// The world buffers (docs/FORMAT.md §5) and how to read their cells.
//
// Generated by naadf-client (client/src/gpu/shaders.rs) from the Rust definitions, in the
// prelude before this file:
// - the parameters \`world_info: WorldInfo\` (size in voxels and chunks, the instance
//   buffer's slots, the step budget);
// - the constants of the cell layout (STATE_*, PAYLOAD, MAX_MATERIAL, VOXEL_SOLID,
//   CHUNK_FIELD_BITS, CELL_FIELD_BITS), the material kinds (KIND_*), the entity layout
//   (ENTITY_SOLID, TYPE_ALIGN, RECORD_WORDS, NO_ENTITY), the instance hierarchy's (NODE_WORDS,
//   BVH_*) and the frame modes (MODE_*);
// - the storage bindings and the accessors \`chunk_word\`, \`block_word\`, \`voxel_word\`,
//   \`material_word\`, \`entity_type_word\`, \`instance_word\`, \`hierarchy_word\` (and
//   \`structure_word\` for the comparison traversals): a buffer larger than the adapter's
//   storage-binding limit is split across several bindings, and the accessor picks the
//   part.

// State of a chunk or block cell: STATE_EMPTY, STATE_FULL or (also for state 3)
// STATE_MIXED.
fn cell_state(c: u32) -> u32 {
    return min(c >> STATE_SHIFT, STATE_MIXED);
}

// Field \`dir\` (order −x, +x, −y, +y, −z, +z) of a packed AADF.
fn aadf_field(word: u32, dir: u32, bits: u32) -> u32 {
    return (word >> (bits * dir)) & ((1u << bits) - 1u);
}

// The index of chunk \`c\` in a world of \`chunks\` chunks (\`world_info.chunks\`). Loops read
// \`world_info\` once before they start and pass its fields: it is a storage buffer, and a
// storage read in every step is a bounds-checked load on lavapipe.
fn chunk_index(c: vec3<u32>, chunks: vec3<u32>) -> u32 {
    return c.x + chunks.x * (c.y + chunks.y * c.z);
}

fn index4(p: vec3<u32>) -> u32 {
    return p.x + 4u * p.y + 16u * p.z;
}

// Voxel \`i\` (0..64) of the voxel group starting at word \`ptr\`.
fn group_voxel(ptr: u32, i: u32) -> u32 {
    return (voxel_word(ptr + i / 2u) >> (16u * (i & 1u))) & 0xFFFFu;
}

// A material's entry (docs/FORMAT.md §5.4).
struct Material {
    kind: u32,
    albedo: vec3<f32>,
    emission: f32,
    roughness: f32,
}

fn material(id: u32) -> Material {
    let w0 = material_word(4u * id);
    let w1 = material_word(4u * id + 1u);
    let w2 = material_word(4u * id + 2u);
    let rg = unpack2x16float(w1);
    let be = unpack2x16float(w2);
    return Material(w0 & 3u, vec3<f32>(rg.x, rg.y, be.x), be.y, unpack2x16float(w0).y);
}

// Rays and the event model every traversal shares (world/src/traverse/ray.rs, in f32).
//
// A ray keeps its origin split into an integer part \`o_int\` and a fraction \`o_frac\` in [0, 1)
// (docs/NAADF.md §9), so precision does not depend on where in the world it starts.
// The direction \`d\` is kept exactly as given (not renormalised, which would move the line
// by an f32 rounding): times are in units of |d| and the ray's \`len\` converts them to
// distances. Every decision compares plane-crossing times from the one function \`t_at\`,
// so the traversal is a consistent walk of the event order "(t, axis), x before y before
// z at equal t"; it departs from the CPU's f64 order only where two crossings are within
// f32 rounding of each other.

// A cell bound beyond any world for unconstrained axes (the CPU walk uses 2^40, which no
// i32 holds).
const FAR_CELL: i32 = 1073741824;
const T_INF: f32 = 3.0e38;
const NO_AXIS: u32 = 3u;

struct Ray {
    o_int: vec3<i32>,
    o_frac: vec3<f32>,
    d: vec3<f32>,
    inv: vec3<f32>,
    len: f32,
}

fn ray_new(o_int: vec3<i32>, o_frac: vec3<f32>, d: vec3<f32>) -> Ray {
    // The inverse of a zero component is never read: such axes never cross a plane.
    let safe = select(vec3<f32>(1.0), d, d != vec3<f32>(0.0));
    return Ray(o_int, o_frac, d, 1.0 / safe, length(d));
}

// A ray from an unsplit origin.
fn ray_from(o: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(o);
    return ray_new(vec3<i32>(fl), min(o - fl, vec3<f32>(0.99999994)), d);
}

// The ray's point at time \`t\`, relative to its integer origin.
fn ray_local(r: Ray, t: f32) -> vec3<f32> {
    return r.o_frac + r.d * t;
}

// A ray starting at \`p\` (relative to \`r\`'s integer origin) along \`d\`.
fn ray_at(r: Ray, p: vec3<f32>, d: vec3<f32>) -> Ray {
    let fl = floor(p);
    return ray_new(r.o_int + vec3<i32>(fl), min(p - fl, vec3<f32>(0.99999994)), d);
}

// Time at which the ray crosses plane \`k\` of \`axis\`.
fn t_at(r: Ray, a: u32, k: i32) -> f32 {
    return (f32(k - r.o_int[a]) - r.o_frac[a]) * r.inv[a];
}

// Whether the crossing of plane \`k\` of axis \`b\` comes before the event \`(t, a)\`.
fn crossed(r: Ray, b: u32, k: i32, t: f32, a: u32) -> bool {
    let tb = t_at(r, b, k);
    return tb < t || (tb == t && b < a);
}

// The cell of axis \`b\` right after event \`(t, a)\`, known to lie in \`lo..=hi\`.
fn cell_after(r: Ray, b: u32, t: f32, a: u32, lo: i32, hi: i32) -> i32 {
    let d = r.d[b];
    if lo == hi || d == 0.0 {
        return lo;
    }
    let p = r.o_frac[b] + d * t;
    let fl = floor(p);
    var k = clamp(i32(fl) + r.o_int[b], lo, hi);
    let f = p - fl;
    // Far from a plane the floor is certain; near one, decide by crossing times.
    let tol = 4e-6 * (abs(d * t) + 1.0);
    if f > tol && f < 1.0 - tol {
        return k;
    }
    if d > 0.0 {
        while k < hi && crossed(r, b, k + 1, t, a) {
            k += 1;
        }
        while k > lo && !crossed(r, b, k, t, a) {
            k -= 1;
        }
    } else {
        while k > lo && crossed(r, b, k, t, a) {
            k -= 1;
        }
        while k < hi && !crossed(r, b, k + 1, t, a) {
            k += 1;
        }
    }
    return k;
}

// Where a ray begins inside the box [0, size): its first cell, the time it is entered and
// the axis whose plane it crossed (NO_AXIS when the origin is inside). \`ok\` is false when
// the ray misses the box.
struct Entry {
    cell: vec3<i32>,
    t: f32,
    axis: u32,
    ok: bool,
}

fn ray_entry(r: Ray, size: vec3<i32>) -> Entry {
    let start = r.o_int;
    var miss = Entry(vec3<i32>(0), 0.0, NO_AXIS, false);
    if all(start >= vec3<i32>(0)) && all(start < size) {
        return Entry(start, 0.0, NO_AXIS, true);
    }
    // The last slab-entry event, in (t, axis) order.
    var bt = 0.0;
    var ba = NO_AXIS;
    for (var a = 0u; a < 3u; a++) {
        var plane: i32;
        if start[a] < 0 {
            if r.d[a] <= 0.0 {
                return miss;
            }
            plane = 0;
        } else if start[a] >= size[a] {
            if r.d[a] >= 0.0 {
                return miss;
            }
            plane = size[a];
        } else {
            continue;
        }
        let t = t_at(r, a, plane);
        if ba == NO_AXIS || t >= bt {
            bt = t;
            ba = a;
        }
    }
    var cell = vec3<i32>(0);
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            cell[b] = select(size[b] - 1, 0, r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            cell[b] = cell_after(r, b, bt, ba, start[b], FAR_CELL);
        } else if r.d[b] < 0.0 {
            cell[b] = cell_after(r, b, bt, ba, -FAR_CELL, start[b]);
        } else {
            cell[b] = start[b];
        }
    }
    if any(cell < vec3<i32>(0)) || any(cell >= size) {
        return miss;
    }
    return Entry(cell, bt, ba, true);
}

// When a ray inside the box [0, size] leaves it: the first crossing of a far plane it moves
// toward (world/src/traverse/ray.rs \`leave_time\`).
fn leave_time(r: Ray, size: vec3<i32>) -> f32 {
    var t = T_INF;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            t = min(t, t_at(r, a, select(0, size[a], r.d[a] > 0.0)));
        }
    }
    return t;
}

// Leaving the empty cuboid made of \`cell\` extended by \`skip\` cells toward the ray on each
// axis: the exit event and the cell entered by it.
struct Exit {
    t: f32,
    axis: u32,
    next: vec3<i32>,
}

fn ray_exit(r: Ray, cell: vec3<i32>, skip: vec3<i32>) -> Exit {
    var bound = vec3<i32>(0);
    var bt = T_INF;
    var ba = 0u;
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] == 0.0 {
            continue;
        }
        bound[a] = select(cell[a] - skip[a], cell[a] + 1 + skip[a], r.d[a] > 0.0);
        let t = t_at(r, a, bound[a]);
        if t < bt {
            bt = t;
            ba = a;
        }
    }
    var next = cell;
    for (var b = 0u; b < 3u; b++) {
        if b == ba {
            next[b] = select(bound[b] - 1, bound[b], r.d[b] > 0.0);
        } else if r.d[b] > 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b], cell[b] + skip[b]);
        } else if r.d[b] < 0.0 {
            next[b] = cell_after(r, b, bt, ba, cell[b] - skip[b], cell[b]);
        }
    }
    return Exit(bt, ba, next);
}

// Amanatides–Woo state in the same event order (ties step the lowest axis first).
struct Dda {
    cell: vec3<i32>,
    tmax: vec3<f32>,
    t: f32,
    axis: u32,
}

fn dda_start(r: Ray, e: Entry) -> Dda {
    var tmax = vec3<f32>(T_INF);
    for (var a = 0u; a < 3u; a++) {
        if r.d[a] != 0.0 {
            tmax[a] = t_at(r, a, select(e.cell[a], e.cell[a] + 1, r.d[a] > 0.0));
        }
    }
    return Dda(e.cell, tmax, e.t, e.axis);
}

fn dda_advance(r: Ray, s: ptr<function, Dda>) {
    var a = 0u;
    if (*s).tmax[1] < (*s).tmax[a] {
        a = 1u;
    }
    if (*s).tmax[2] < (*s).tmax[a] {
        a = 2u;
    }
    (*s).t = (*s).tmax[a];
    let c = (*s).cell[a] + select(-1, 1, r.d[a] > 0.0);
    (*s).cell[a] = c;
    (*s).axis = a;
    (*s).tmax[a] = t_at(r, a, select(c, c + 1, r.d[a] > 0.0));
}

// The first solid voxel along a ray (of the world, or of an entity: then voxel and normal
// are entity-local).
struct Hit {
    hit: bool,
    // The step budget ran out (counts as a miss).
    exhausted: bool,
    voxel: vec3<i32>,
    // Axis of the entry face (NO_AXIS: the origin was inside the voxel).
    axis: u32,
    // Entry-face normal (zero when the origin was inside).
    normal: vec3<i32>,
    // Time of entry, in units of the ray's |d|.
    t: f32,
    material: u32,
    steps: u32,
    // Entity id, or NO_ENTITY (generated in the prelude).
    entity: u32,
}

fn no_hit(steps: u32) -> Hit {
    return Hit(false, false, vec3<i32>(0), NO_AXIS, vec3<i32>(0), T_INF, 0u, steps, NO_ENTITY);
}

fn make_hit(r: Ray, cell: vec3<i32>, t: f32, axis: u32, material: u32, steps: u32) -> Hit {
    var n = vec3<i32>(0);
    if axis != NO_AXIS {
        n[axis] = select(1, -1, r.d[axis] > 0.0);
    }
    return Hit(true, false, cell, axis, n, t, material, steps, NO_ENTITY);
}

// One full trace: the world loop (traverse.wgsl or grid.wgsl) through the static world,
// then the instances whose world boxes the ray crosses before the world's hit or exit,
// found through their hierarchy (docs/NAADF.md §11): the GPU twin of
// world/src/traverse/entities.rs. Only the nearest entity hit (lowest id at equal times)
// survives, and only if it comes strictly before the world's hit or exit. Local instances
// (previews, markers: world/src/entity/local.rs) follow the world's records and carry the id
// NO_ENTITY, so their hits read as static geometry to everything that follows entity ids.

// How the world loop ended.
const END_HIT: u32 = 0u;
const END_LEFT: u32 = 1u;
const END_MISSED: u32 = 2u;
const END_EXHAUSTED: u32 = 3u;

struct WorldTrace {
    hit: Hit,
    end: u32,
    // When the ray entered the world, and when it hit or left it.
    t_entry: f32,
    t_end: f32,
}

// The end of a world loop whose step budget ran out at time \`t\` (entered at \`t_entry\`).
fn ran_out(t_entry: f32, t: f32) -> WorldTrace {
    var h = no_hit(world_info.max_steps);
    h.exhausted = true;
    return WorldTrace(h, END_EXHAUSTED, t_entry, t);
}

var<private> best_entity: Hit;
// The inverse rotation of \`best_entity\`'s instance.
var<private> best_rotation: vec4<f32>;
// Entity-grid cells visited (added to the step count of an entity hit).
var<private> entity_steps: u32;
// Whether the last \`trace\` returned an instance's hit (a local instance's has no entity id).
var<private> hit_instance: bool;

// Whether the world holds any instance. The host builds a pipeline for each value and
// picks the one that matches its world: a device that runs neighbouring rays in lock step
// may run code that no ray takes, and without instances none of the walk is compiled.
override HAS_INSTANCES: bool = true;

// How many instances the walk finds before it stops to test them.
const INSTANCE_BATCH: u32 = 8u;

// The walk's node stack and found instances, at module scope, so that an invocation holds
// (and zeroes) one of each rather than one for every trace inlined into it.
var<private> bvh_stack: array<u32, BVH_STACK>;
var<private> found_t: array<f32, INSTANCE_BATCH>;
var<private> found_slot: array<u32, INSTANCE_BATCH>;

// Walks the instance hierarchy (world/src/entity/bvh.rs: four-wide nodes of NODE_WORDS
// words, the children's f32 boxes axis by axis, then their references) and tests every
// instance whose box the ray is inside at some t in [t_lo, t_hi] (or up to the best entity
// hit so far). Boxes are padded and rounded outward, so the f32 test never rejects an
// instance the ray can hit. The walk gathers up to INSTANCE_BATCH instances, then tests them
// in the order the ray enters their boxes, stopping at a box that starts after the best hit,
// and goes on while nodes are left. Testing outside the walk's loop keeps that loop small,
// which is what costs on a device that runs neighbouring rays in lock step. With \`any_hit\`
// it returns at the first hit before \`t_hi\`.
fn find_instances(r: Ray, t_lo: f32, t_hi: f32, any_hit: bool) {
    // The world loop says whether its structure is traced with entities: the comparison
    // trees hold geometry only.
    if !TRACES_ENTITIES || !HAS_INSTANCES || world_info.instance_slots == 0u {
        return;
    }
    // 1/d, with ±FAR for axes the ray does not move along.
    let inv = select(1.0 / r.d, select(vec3<f32>(BVH_FAR), vec3<f32>(-BVH_FAR), r.d < vec3<f32>(0.0)), r.d == vec3<f32>(0.0));
    let o = vec3<f32>(r.o_int);
    bvh_stack[0] = 0u;
    var sp = 1u;
    while sp > 0u {
        var far_limit = t_hi * 1.000001 + 1e-3;
        if best_entity.hit {
            far_limit = min(far_limit, best_entity.t * 1.000001 + 1e-3);
        }
        // A node adds at most four instances, so one is taken while four places are left.
        var found = 0u;
        while sp > 0u && found + 4u <= INSTANCE_BATCH {
            sp -= 1u;
            let base = bvh_stack[sp] * NODE_WORDS;
            // The four lanes at once, axis by axis.
            let tx0 = ((node_lanes(base) - o.x) - r.o_frac.x) * inv.x;
            let tx1 = ((node_lanes(base + 4u) - o.x) - r.o_frac.x) * inv.x;
            let ty0 = ((node_lanes(base + 8u) - o.y) - r.o_frac.y) * inv.y;
            let ty1 = ((node_lanes(base + 12u) - o.y) - r.o_frac.y) * inv.y;
            let tz0 = ((node_lanes(base + 16u) - o.z) - r.o_frac.z) * inv.z;
            let tz1 = ((node_lanes(base + 20u) - o.z) - r.o_frac.z) * inv.z;
            let near = max(vec4<f32>(t_lo - 1e-3), max(min(tx0, tx1), max(min(ty0, ty1), min(tz0, tz1))));
            let far = min(vec4<f32>(far_limit), min(max(tx0, tx1), min(max(ty0, ty1), max(tz0, tz1))));
            let child = vec4<u32>(hierarchy_word(base + 24u), hierarchy_word(base + 25u), hierarchy_word(base + 26u), hierarchy_word(base + 27u));
            let entered = !(near > far) & (child != vec4<u32>(BVH_NONE));
            // Each lane in turn: no loop, so that no lane's index is dynamic.
            if entered.x {
                keep_lane(child.x, near.x, &sp, &found);
            }
            if entered.y {
                keep_lane(child.y, near.y, &sp, &found);
            }
            if entered.z {
                keep_lane(child.z, near.z, &sp, &found);
            }
            if entered.w {
                keep_lane(child.w, near.w, &sp, &found);
            }
        }
        // Nearest box first, until one starts after the best hit (whose own box started no
        // later: the boxes are padded beyond the f32 test's rounding).
        for (var left = found; left > 0u; left--) {
            var k = 0u;
            for (var j = 1u; j < left; j++) {
                if found_t[j] < found_t[k] {
                    k = j;
                }
            }
            if best_entity.hit && found_t[k] > best_entity.t {
                break;
            }
            test_instance(r, found_slot[k] * RECORD_WORDS, t_lo);
            if any_hit && best_entity.hit && best_entity.t < t_hi {
                return;
            }
            found_t[k] = found_t[left - 1u];
            found_slot[k] = found_slot[left - 1u];
        }
    }
}

// Keeps a lane the ray enters at \`near\`: an instance among the found ones, or a node on the
// stack.
fn keep_lane(c: u32, near: f32, sp: ptr<function, u32>, found: ptr<function, u32>) {
    if (c & BVH_LEAF) != 0u {
        found_t[*found] = near;
        found_slot[*found] = c & ~BVH_LEAF;
        *found += 1u;
    } else if *sp < BVH_STACK {
        bvh_stack[*sp] = c;
        *sp += 1u;
    }
}

// Four lanes' planes of one axis, from word \`at\` of the hierarchy.
fn node_lanes(at: u32) -> vec4<f32> {
    return bitcast<vec4<f32>>(vec4<u32>(hierarchy_word(at), hierarchy_word(at + 1u), hierarchy_word(at + 2u), hierarchy_word(at + 3u)));
}

// Decodes a smallest-three quaternion (world/src/entity/pack.rs).
fn decode_quat(w0: u32, w1: u32) -> vec4<f32> {
    let s = vec3<f32>(vec3<u32>(w0 & 0x3FFFu, (w0 >> 14u) & 0x3FFFu, (w0 >> 28u) | ((w1 & 0x3FFu) << 4u)));
    let small = (s - 8192.0) / 8192.0;
    let rest = sqrt(max(1.0 - dot(small, small), 0.0));
    let k = (w1 >> 10u) & 3u;
    if k == 0u {
        return vec4<f32>(rest, small.x, small.y, small.z);
    } else if k == 1u {
        return vec4<f32>(small.x, rest, small.y, small.z);
    } else if k == 2u {
        return vec4<f32>(small.x, small.y, rest, small.z);
    }
    return vec4<f32>(small, rest);
}

// Rotates \`v\` by the unit quaternion \`q = (x, y, z, w)\`.
fn rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

fn conjugate(q: vec4<f32>) -> vec4<f32> {
    return vec4<f32>(-q.xyz, q.w);
}

// An instance record's position in 1/128 voxel (record words 0 and 1).
fn record_position(dx: u32, dy: u32) -> vec3<u32> {
    return vec3<u32>(dx & 0x1FFFFFu, (dx >> 21u) | (((dy >> 21u) & 0xFFu) << 11u), dy & 0x1FFFFFu);
}

// An instance record's entity id (record word 4).
fn record_id(e: u32) -> u32 {
    return e & 0x3FFFu;
}

// Tests the instance record at word \`at\` against the ray; keeps the nearest entity hit.
fn test_instance(r: Ray, at: u32, t_lo: f32) {
    let dx = instance_word(at);
    let dy = instance_word(at + 1u);
    let dz = instance_word(at + 2u);
    let dw = instance_word(at + 3u);
    let e = instance_word(at + 4u);
    let id = record_id(e);
    let size = vec3<u32>((e >> 14u) & 0x7Fu, (e >> 21u) & 0x7Fu, ((e >> 28u) & 0xFu) | (((dy >> 29u) & 7u) << 4u));
    let pos = record_position(dx, dy);
    var limit = T_INF;
    var equal_ok = false;
    if best_entity.hit {
        limit = best_entity.t;
        equal_ok = id < best_entity.entity;
    }
    // The entity lies within |size| of its local-origin corner: reject rays that pass
    // farther (with slack for f32), before transforming anything.
    let rel = vec3<f32>(r.o_int - vec3<i32>(pos >> vec3<u32>(7u))) + (r.o_frac - vec3<f32>(pos & vec3<u32>(127u)) / 128.0);
    let tc = -dot(rel, r.d) / (r.len * r.len);
    let radius = (length(vec3<f32>(size)) + 0.01) / r.len;
    let closest = rel + r.d * tc;
    if dot(closest, closest) > radius * radius * r.len * r.len || tc + radius < t_lo || tc - radius > limit {
        return;
    }
    let q = decode_quat(dz, dw & 0xFFFu);
    let local = ray_from(rotate(q, rel), rotate(q, r.d));
    let isize = vec3<i32>(size);
    let entry = ray_entry(local, isize);
    if !entry.ok {
        return;
    }
    let base = (dw >> 12u) * TYPE_ALIGN;
    var s = dda_start(local, entry);
    loop {
        entity_steps += 1u;
        if s.t > limit || (s.t == limit && !equal_ok) {
            return;
        }
        if s.t >= t_lo {
            let c = vec3<u32>(s.cell);
            let v = entity_type_word(base + c.x + size.x * (c.y + size.y * c.z));
            if (v & ENTITY_SOLID) != 0u {
                var h = make_hit(local, s.cell, s.t, s.axis, v & MAX_MATERIAL, 0u);
                h.entity = id;
                best_entity = h;
                best_rotation = q;
                return;
            }
        }
        dda_advance(local, &s);
        if any(s.cell < vec3<i32>(0)) || any(s.cell >= isize) {
            return;
        }
    }
}

// The world-space normal of the hit the last \`trace\` returned (entity-local normals are
// rotated back to the world).
fn world_normal(h: Hit) -> vec3<f32> {
    let n = vec3<f32>(h.normal);
    if !hit_instance {
        return n;
    }
    return rotate(conjugate(best_rotation), n);
}

// Clears the entity state of the last trace and runs the world loop: how a trace starts.
fn world_first(r: Ray) -> WorldTrace {
    entity_steps = 0u;
    best_entity = no_hit(0u);
    hit_instance = false;
    return world_loop(r);
}

// Traces \`r\` through the world and its entities.
fn trace(r: Ray) -> Hit {
    let w = world_first(r);
    if w.end == END_MISSED || w.end == END_EXHAUSTED {
        return w.hit;
    }
    find_instances(r, w.t_entry, w.t_end, false);
    if best_entity.hit && best_entity.t < w.t_end {
        hit_instance = true;
        var h = best_entity;
        h.steps = w.hit.steps + entity_steps;
        return h;
    }
    var h = w.hit;
    h.steps += entity_steps;
    return h;
}

// Whether \`trace(r)\` would hit (\`x\`) and whether it would run out of steps (\`y\`), for rays
// that only ask whether something is in the way (shadow rays): a ray that hits the world
// needs no instance walk, and one that leaves it stops walking at the first instance hit.
fn occlusion(r: Ray) -> vec2<bool> {
    let w = world_first(r);
    if w.end != END_LEFT {
        return vec2<bool>(w.hit.hit, w.hit.exhausted);
    }
    find_instances(r, w.t_entry, w.t_end, true);
    return vec2<bool>(best_entity.hit && best_entity.t < w.t_end, false);
}

// The world loop over the chunk → block → voxel hierarchy (docs/NAADF.md §9), with
// AADF jumps (\`USE_AADF\`, the \`naadf\` method) or without (\`nodf\`): the GPU twin of
// world/src/traverse/hierarchy.rs. It sees the static world alone: entities are found
// afterwards, through their hierarchy (trace.wgsl).

override USE_AADF: bool = true;
// Entities are found after the loop (see trace.wgsl).
const TRACES_ENTITIES: bool = true;


fn to_edge(c: u32, neg: bool, edge: u32) -> i32 {
    let m = c & (edge - 1u);
    return i32(select(edge - 1u - m, m, neg));
}

fn world_loop(r: Ray) -> WorldTrace {
    let dims = vec3<i32>(world_info.size);
    let entry = ray_entry(r, dims);
    if !entry.ok {
        return WorldTrace(no_hit(0u), END_MISSED, 0.0, 0.0);
    }
    var cell = entry.cell;
    var t = entry.t;
    var axis = entry.axis;
    let neg = r.d <= vec3<f32>(0.0);
    // The AADF field facing the ray on each axis: −a for negative directions, +a otherwise.
    let facing = vec3<u32>(0u, 2u, 4u) + select(vec3<u32>(0u), vec3<u32>(1u), r.d > vec3<f32>(0.0));
    // The world's parameters, read once (see chunk_index in world.wgsl).
    let chunks = world_info.chunks;
    let max_steps = world_info.max_steps;
    for (var steps = 1u; steps <= max_steps; steps++) {
        let p = vec3<u32>(cell);
        let chunk = chunk_word(chunk_index(p >> vec3<u32>(4u), chunks));
        var skip = vec3<i32>(0);
        let cs = cell_state(chunk);
        if cs == STATE_FULL {
            return WorldTrace(make_hit(r, cell, t, axis, chunk & MAX_MATERIAL, steps), END_HIT, entry.t, t);
        } else if cs == STATE_EMPTY {
            for (var a = 0u; a < 3u; a++) {
                skip[a] = to_edge(p[a], neg[a], 16u);
                if USE_AADF {
                    skip[a] += 16 * i32(aadf_field(chunk, facing[a], CHUNK_FIELD_BITS));
                }
            }
        } else {
            let block = block_word((chunk & PAYLOAD) + index4((p >> vec3<u32>(2u)) & vec3<u32>(3u)));
            let bs = cell_state(block);
            if bs == STATE_FULL {
                return WorldTrace(make_hit(r, cell, t, axis, block & MAX_MATERIAL, steps), END_HIT, entry.t, t);
            } else if bs == STATE_EMPTY {
                for (var a = 0u; a < 3u; a++) {
                    skip[a] = to_edge(p[a], neg[a], 4u);
                    if USE_AADF {
                        skip[a] += 4 * i32(aadf_field(block, facing[a], CELL_FIELD_BITS));
                    }
                }
            } else {
                let v = group_voxel(block & PAYLOAD, index4(p & vec3<u32>(3u)));
                if (v & VOXEL_SOLID) != 0u {
                    return WorldTrace(make_hit(r, cell, t, axis, v & MAX_MATERIAL, steps), END_HIT, entry.t, t);
                }
                if USE_AADF {
                    for (var a = 0u; a < 3u; a++) {
                        skip[a] = i32(aadf_field(v, facing[a], CELL_FIELD_BITS));
                    }
                }
            }
        }
        let ex = ray_exit(r, cell, skip);
        if any(ex.next < vec3<i32>(0)) || any(ex.next >= dims) {
            // An AADF box may reach beyond the world: the ray left it at the world's edge.
            return WorldTrace(no_hit(steps), END_LEFT, entry.t, min(ex.t, leave_time(r, dims)));
        }
        cell = ex.next;
        t = ex.t;
        axis = ex.axis;
    }
    return ran_out(entry.t, t);
}

// The samples of the lit passes: random streams (client/src/light/rng.rs), one per sample
// of each pixel, seeded from the run's seed, the pixel's index and the sample's number
// only; and the jittered camera ray of a sample.

fn pcg_hash(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

// The stream of sample \`sample\` of pixel \`pixel\` under \`seed\`.
fn rng_new(seed: u32, pixel: u32, sample: u32) -> u32 {
    return pcg_hash(seed ^ pcg_hash(pixel ^ pcg_hash(sample)));
}

// A uniform number in [0, 1) with 24 random bits.
fn rng_next(state: ptr<function, u32>) -> f32 {
    *state = pcg_hash(*state);
    return f32(*state >> 8u) * (1.0 / 16777216.0);
}

// The stream of sample \`sample\` of pixel \`pixel\`, after its first two draws: where in the
// pixel the sample's camera ray goes (uniform in [0, 1)²).
struct PixelStream {
    rng: u32,
    jitter: vec2<f32>,
}

fn pixel_stream(seed: u32, pixel: u32, sample: u32) -> PixelStream {
    var rng = rng_new(seed, pixel, sample);
    let jx = rng_next(&rng);
    let jy = rng_next(&rng);
    return PixelStream(rng, vec2<f32>(jx, jy));
}

// The camera's (unnormalised) direction through point \`jitter\` ([0, 1)²) of pixel \`gid\` of
// frame \`f\` (docs/CAMERA.md, with \`px + jitter.x\` for \`px + 0.5\`).
fn camera_dir(f: FrameInfo, gid: vec2<u32>, jitter: vec2<f32>) -> vec3<f32> {
    let sx = 2.0 * (f32(gid.x) + jitter.x) / f32(f.width) - 1.0;
    let sy = 1.0 - 2.0 * (f32(gid.y) + jitter.y) / f32(f.height);
    return f.forward + sx * f.right + sy * f.up;
}

// The light model of the lit modes (docs/RENDERING.md §3a): the physical sky, the sun,
// BRDF sampling and one path's radiance. The GPU twin of client/src/light/ (sky.rs,
// scatter.rs, cpu.rs), written operation by operation like it so that the two path
// tracers agree up to rounding. Needs random.wgsl before it.
//
// The pass binds \`light: LightInfo\` (generated in the prelude from the Rust \`LightInfo\`),
// and declares \`DIFFUSE_TIER\` and \`diffuse_tier\` (no_tier.wgsl, or a lighting tier such as
// roma.wgsl) for \`path_step\`.

// PI, SURFACE_OFFSET (how far scattered and shadow rays start off the surface),
// MIN_ALPHA (the smallest GGX α a metal is traced with) and the physical sky's constants
// (PLANET_RADIUS, VIEW_STEPS, RAYLEIGH, MIE_G, OZONE, …) come from the prelude, generated
// from their Rust definitions in client/src/light/ (mod.rs, scatter.rs, sky.rs).

// ---- The physical sky (sky.rs) ----

// Distance from height \`h\` along zenith cosine \`mu\` to the sphere at height \`top\`; a
// negative value when it is not reached going forward.
fn sphere_distance(h: f32, mu: f32, top: f32) -> f32 {
    let r = PLANET_RADIUS + h;
    let disc = (top - h) * (2.0 * PLANET_RADIUS + top + h) + r * r * mu * mu;
    if disc < 0.0 {
        return -1.0;
    }
    let s = sqrt(disc);
    let far = -r * mu + s;
    if far < 0.0 {
        return -1.0;
    }
    let near = -r * mu - s;
    return select(far, near, near > 0.0);
}

struct Medium {
    sigma: vec3<f32>,
    rayleigh: f32,
    mie: f32,
}

fn medium(h: f32) -> Medium {
    let rayleigh = exp(-h / RAYLEIGH_SCALE);
    let mie = exp(-h / MIE_SCALE);
    let ozone = max(1.0 - abs(h - OZONE_CENTRE) / OZONE_HALF_WIDTH, 0.0);
    return Medium(RAYLEIGH * rayleigh + MIE_EXTINCTION * mie + OZONE * ozone, rayleigh, mie);
}

fn sun_transmittance(h: f32, mu: f32) -> vec3<f32> {
    if mu < 0.0 && sphere_distance(h, mu, 0.0) >= 0.0 {
        return vec3<f32>(0.0);
    }
    let length = max(sphere_distance(h, mu, ATMOSPHERE_HEIGHT), 0.0);
    let dt = length / f32(LIGHT_STEPS);
    let r = PLANET_RADIUS + h;
    var depth = vec3<f32>(0.0);
    for (var i = 0u; i < LIGHT_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let hi = sqrt(t * t + 2.0 * r * mu * t + r * r) - PLANET_RADIUS;
        depth += medium(hi).sigma * dt;
    }
    return exp(-depth);
}

// Sky radiance along unit \`dir\` for unit sun direction \`sun\`, per unit of irradiance.
fn sky_physical(dir: vec3<f32>, sun: vec3<f32>) -> vec3<f32> {
    let mu = dir.y;
    let nu = dot(dir, sun);
    let h0 = EYE_HEIGHT;
    let r0 = PLANET_RADIUS + h0;
    var length = sphere_distance(h0, mu, 0.0);
    if !(mu < 0.0 && length >= 0.0) {
        length = max(sphere_distance(h0, mu, ATMOSPHERE_HEIGHT), 0.0);
    }
    let dt = length / f32(VIEW_STEPS);
    let phase_r = 3.0 / (16.0 * PI) * (1.0 + nu * nu);
    let g2 = MIE_G * MIE_G;
    let phase_m = (1.0 - g2) / (4.0 * PI * pow(1.0 + g2 - 2.0 * MIE_G * nu, 1.5));
    var depth = vec3<f32>(0.0);
    var inscatter = vec3<f32>(0.0);
    for (var i = 0u; i < VIEW_STEPS; i++) {
        let t = (f32(i) + 0.5) * dt;
        let r = sqrt(t * t + 2.0 * r0 * mu * t + r0 * r0);
        let h = r - PLANET_RADIUS;
        let mu_sun = (r0 * sun.y + t * nu) / r;
        let m = medium(h);
        let to_sun = sun_transmittance(h, mu_sun);
        let view = exp(-(depth + 0.5 * m.sigma * dt));
        let scatter = RAYLEIGH * m.rayleigh * phase_r + MIE_SCATTER * m.mie * phase_m;
        inscatter += view * to_sun * scatter * dt;
        depth += m.sigma * dt;
    }
    return inscatter;
}

// The sky along unit \`d\`, evaluated directly (no disc).
fn sky_direct(d: vec3<f32>) -> vec3<f32> {
    if light.sky_physical != 0u {
        return sky_physical(d, light.sun_dir) * light.sky;
    }
    return light.sky;
}

// The sky along unit \`d\`; with \`disc\`, the sun's disc too. \`sky_base(d)\` is the including
// pass's choice: \`sky_direct\` (the path tracer) or the atmosphere table (\`gi\`).
fn sky_radiance(d: vec3<f32>, disc: bool) -> vec3<f32> {
    var l = sky_base(d);
    if disc {
        l += sun_disc(d);
    }
    return l;
}

// The sun's disc along unit \`d\` (0 off the disc, or with the sun off).
fn sun_disc(d: vec3<f32>) -> vec3<f32> {
    if light.sun_on != 0u && 1.0 - dot(d, light.sun_dir) <= light.sun_omc {
        return vec3<f32>(light.sun_disc);
    }
    return vec3<f32>(0.0);
}

// ---- Scattering (scatter.rs) ----

struct Basis {
    t: vec3<f32>,
    b: vec3<f32>,
}

fn basis(n: vec3<f32>) -> Basis {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return Basis(vec3<f32>(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3<f32>(b, sign + n.y * n.y * a, -n.y));
}

fn sample_cosine(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let f = basis(n);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (r * cos(phi)) + f.b * (r * sin(phi)) + n * sqrt(max(1.0 - u.x, 0.0)));
}

fn sample_cone(axis: vec3<f32>, omc: f32, u: vec2<f32>) -> vec3<f32> {
    let f = basis(axis);
    let x = u.x * omc;
    let c = 1.0 - x;
    let s = sqrt(max(x * (2.0 - x), 0.0));
    let phi = 2.0 * PI * u.y;
    return normalize(f.t * (s * cos(phi)) + f.b * (s * sin(phi)) + axis * c);
}

fn schlick(f0: vec3<f32>, c: f32) -> vec3<f32> {
    let k = 1.0 - clamp(c, 0.0, 1.0);
    let k2 = k * k;
    return f0 + (vec3<f32>(1.0) - f0) * (k2 * k2 * k);
}

fn smith_lambda(alpha: f32, c: f32) -> f32 {
    let c2 = max(c * c, 1e-12);
    let tan2 = max(1.0 - c2, 0.0) / c2;
    return 0.5 * (-1.0 + sqrt(1.0 + alpha * alpha * tan2));
}

fn ggx_d(alpha: f32, c: f32) -> f32 {
    let a2 = alpha * alpha;
    let k = c * c * (a2 - 1.0) + 1.0;
    return a2 / (PI * k * k);
}

fn ggx(n: vec3<f32>, wo: vec3<f32>, wi: vec3<f32>, alpha: f32, f0: vec3<f32>) -> vec3<f32> {
    let co = dot(n, wo);
    let ci = dot(n, wi);
    if co <= 0.0 || ci <= 0.0 {
        return vec3<f32>(0.0);
    }
    let h = normalize(wo + wi);
    let g2 = 1.0 / (1.0 + smith_lambda(alpha, co) + smith_lambda(alpha, ci));
    return schlick(f0, dot(wo, h)) * (ggx_d(alpha, dot(n, h)) * g2 / (4.0 * co * ci));
}

struct Scattered {
    dir: vec3<f32>,
    weight: vec3<f32>,
}

fn ggx_sample(n: vec3<f32>, wo: vec3<f32>, alpha: f32, f0: vec3<f32>, u: vec2<f32>) -> Scattered {
    let f = basis(n);
    let v = vec3<f32>(dot(wo, f.t), dot(wo, f.b), dot(wo, n));
    let vh = normalize(vec3<f32>(alpha * v.x, alpha * v.y, v.z));
    let lensq = vh.x * vh.x + vh.y * vh.y;
    var t1 = vec3<f32>(1.0, 0.0, 0.0);
    if lensq > 0.0 {
        t1 = vec3<f32>(-vh.y, vh.x, 0.0) / sqrt(lensq);
    }
    let t2 = cross(vh, t1);
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let p1 = r * cos(phi);
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * sqrt(max(1.0 - p1 * p1, 0.0)) + s * r * sin(phi);
    let nh = t1 * p1 + t2 * p2 + vh * sqrt(max(1.0 - p1 * p1 - p2 * p2, 0.0));
    let m = normalize(vec3<f32>(alpha * nh.x, alpha * nh.y, max(nh.z, 0.0)));
    let lwi = m * (2.0 * dot(v, m)) - v;
    let wi = normalize(f.t * lwi.x + f.b * lwi.y + n * lwi.z);
    let lo = smith_lambda(alpha, v.z);
    let li = smith_lambda(alpha, lwi.z);
    return Scattered(wi, schlick(f0, dot(v, m)) * ((1.0 + lo) / (1.0 + lo + li)));
}

// ---- Paths (cpu.rs) ----

// Whether a shadow ray meets anything before leaving the world (a ray out of cells counts
// as blocked).
fn blocked(r: Ray, p: vec3<f32>, dir: vec3<f32>) -> bool {
    return any(occlusion(ray_at(r, p, dir)));
}

// One sample of the sun's disc seen from \`p\` (relative to \`r\`'s integer origin, just off a
// surface of normal \`n\`): its direction, and the irradiance it brings (\`E·cosθ\`-weighted)
// when it is above the surface and unblocked, else 0. Two random numbers are drawn
// whenever the sun is on (cpu.rs \`sun_sample\`).
struct SunSample {
    dir: vec3<f32>,
    irradiance: f32,
}

fn sun_sample(r: Ray, p: vec3<f32>, n: vec3<f32>, rng: ptr<function, u32>) -> SunSample {
    if light.sun_on == 0u {
        return SunSample(vec3<f32>(0.0), 0.0);
    }
    let u = vec2<f32>(rng_next(rng), rng_next(rng));
    let wi = sample_cone(light.sun_dir, light.sun_omc, u);
    let c = dot(n, wi);
    if c > 0.0 && !blocked(r, p, wi) {
        return SunSample(wi, c * light.sun_weight);
    }
    return SunSample(wi, 0.0);
}

// One step of a path: what it adds and whether it goes on.
struct PathState {
    r: Ray,
    radiance: vec3<f32>,
    throughput: vec3<f32>,
    sees_disc: bool,
    alive: bool,
    // The normal of the first surface met (zero until then).
    first_normal: vec3<f32>,
}

// Follows the path in \`s\` to its next surface: adds the light found there and, when
// \`scatter\`, picks the next ray (or ends the path). Returns the distance to the surface
// (−1 when the ray found none).
fn path_step(s: ptr<function, PathState>, scatter: bool, rng: ptr<function, u32>) -> f32 {
    let r = (*s).r;
    let h = trace(r);
    let d = r.d / r.len;
    (*s).alive = false;
    if h.exhausted {
        return -1.0;
    }
    if !h.hit {
        (*s).radiance += (*s).throughput * sky_radiance(d, (*s).sees_disc);
        return -1.0;
    }
    let distance = h.t * r.len;
    if h.axis == NO_AXIS {
        return distance;
    }
    // Before any other trace: world_normal reads the last trace's entity rotation.
    let n = world_normal(h);
    if all((*s).first_normal == vec3<f32>(0.0)) {
        (*s).first_normal = n;
    }
    let m = material(h.material);
    if m.kind == KIND_EMISSIVE {
        (*s).radiance += (*s).throughput * m.albedo * m.emission;
    }
    // A lighting tier (\`roma\`, \`irradiance\`) lights diffuse and emissive surfaces itself,
    // and the path ends there; mirrors and metals scatter on.
    if DIFFUSE_TIER && m.kind != KIND_MIRROR && m.kind != KIND_METAL {
        let surface = vec3<f32>(r.o_int) + ray_local(r, h.t);
        (*s).radiance += (*s).throughput * diffuse_tier(h, surface, n, m.albedo, rng);
        return distance;
    }
    if !scatter {
        return distance;
    }
    let p = ray_local(r, h.t) + n * SURFACE_OFFSET;
    var next: Scattered;
    if m.kind == KIND_MIRROR {
        (*s).sees_disc = true;
        next = Scattered(d - n * (2.0 * dot(d, n)), m.albedo);
    } else {
        let wo = -d;
        let alpha = max(m.roughness, MIN_ALPHA);
        let sun = sun_sample(r, p, n, rng);
        if sun.irradiance > 0.0 {
            var f = m.albedo / PI;
            if m.kind == KIND_METAL {
                f = ggx(n, wo, sun.dir, alpha, m.albedo);
            }
            (*s).radiance += (*s).throughput * f * sun.irradiance;
        }
        let u = vec2<f32>(rng_next(rng), rng_next(rng));
        (*s).sees_disc = false;
        if m.kind == KIND_METAL {
            next = ggx_sample(n, wo, alpha, m.albedo, u);
        } else {
            next = Scattered(sample_cosine(n, u), m.albedo);
        }
    }
    if dot(next.dir, n) > 0.0 {
        (*s).throughput *= next.weight;
        (*s).r = ray_at(r, p, next.dir);
        (*s).alive = true;
    }
    return distance;
}

// One path: the radiance it brought back, the distance from its origin to the first
// surface (−1 for the sky) and that surface's normal.
struct PathSample {
    radiance: vec3<f32>,
    distance: f32,
    normal: vec3<f32>,
}

// The radiance arriving along \`primary\` when the path may scatter \`bounces\` more times,
// drawing from \`rng\`. \`sees_disc\`: whether the ray sees the sun's disc (camera and mirror
// rays do; rays scattered by other surfaces get the sun by next-event estimation instead).
fn path_radiance(primary: Ray, bounces: u32, sees_disc: bool, rng: ptr<function, u32>) -> PathSample {
    var s = PathState(primary, vec3<f32>(0.0), vec3<f32>(1.0), sees_disc, true, vec3<f32>(0.0));
    let distance = path_step(&s, bounces > 0u, rng);
    for (var bounce = 1u; bounce <= bounces && s.alive; bounce++) {
        path_step(&s, bounce < bounces, rng);
    }
    return PathSample(s.radiance, distance, s.first_normal);
}

// No lighting tier: \`path_step\` (light.wgsl) traces diffuse surfaces as the light model
// does. Included by the path tracer, the GI passes and the irradiance cache's updates;
// \`roma\` and \`irradiance\` include roma.wgsl and irradiance.wgsl instead.

const DIFFUSE_TIER: bool = false;

fn diffuse_tier(h: Hit, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, u32>) -> vec3<f32> {
    return vec3<f32>(0.0);
}

// The irradiance cache's table (\`irradiance\`; docs/RENDERING.md §3e), shared by its sample
// pass (irradiance.wgsl) and its update passes (irradiance_update.wgsl). The GPU twin of
// client/src/light/irradiance/, which states the rules.
//
// A slot is IRR_WORDS words: the key's two words (FaceKey::words; both non-zero, an empty
// slot's are zero), the stamp of the last frame that requested it, the count of samples
// its mean holds, the sums of those samples (RGB, f32 bits), and the samples ever drawn
// (the next sample's number). Keys are placed by linear probing from \`irr_stream(key) &
// mask\`, and only a whole clear removes them.
//
// The request list: IRR_COUNT (slots requested this frame), IRR_FRESH (those with no
// samples), IRR_TAKEN (samples taken), IRR_OCCUPIED (slots keyed, kept across frames),
// then from IRR_LIST the slots.
// IRR_* and \`IrradianceInfo\` are generated by client/src/gpu/irradiance.rs.

// The stream of the entry of \`key\`: its home slot and its samples' random streams.
fn irr_stream(key: vec2<u32>) -> u32 {
    return pcg_hash(key.x ^ pcg_hash(key.y));
}

// The irradiance cache's update passes (\`irradiance\`; docs/RENDERING.md §3e), with
// irradiance_table.wgsl and the path tracer's light.wgsl (no tier):
// - \`irradiance_invalidate\`, one invocation per slot: clears the samples of every entry
//   whose voxel lies in one of the boxes (the changed chunks grown by the bounce distance);
// - \`irradiance_args\`, one invocation: the update pass's dispatch from the request count;
// - \`irradiance_update\`, one invocation per requested slot: takes the entry's next sample
//   when the frame's budget allows (client/src/light/irradiance/ states the sample).

@group(1) @binding(0) var<uniform> light: LightInfo;
@group(1) @binding(1) var<uniform> irr: IrradianceInfo;
@group(1) @binding(2) var<storage, read_write> irr_table: array<u32>;
@group(1) @binding(3) var<storage, read_write> irr_requests: array<atomic<u32>>;
@group(1) @binding(4) var<storage, read> irr_boxes: array<vec4<i32>>;
// \`irradiance_args\` only: the update's indirect dispatch.
@group(1) @binding(5) var<storage, read_write> irr_args: array<u32>;

// Rays leaving a face see the sky as the path tracer does.
fn sky_base(d: vec3<f32>) -> vec3<f32> {
    return sky_direct(d);
}

// The voxel of the key in slot words \`at\`.
fn irr_voxel(at: u32) -> vec3<i32> {
    let a = irr_table[at];
    return vec3<i32>(vec3<u32>(a & 0x7FFFu, irr_table[at + 1u] & 0xFFFFu, a >> 16u));
}

@compute @workgroup_size(64)
fn irradiance_invalidate(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let slot = gid.x + gid.y * groups.x * 64u;
    if slot > irr.mask {
        return;
    }
    let at = slot * IRR_WORDS;
    if irr_table[at + 1u] == 0u || irr_table[at + 3u] == 0u {
        return;
    }
    let v = irr_voxel(at);
    for (var i = 0u; i < irr.boxes; i++) {
        if all(v >= irr_boxes[2u * i].xyz) && all(v <= irr_boxes[2u * i + 1u].xyz) {
            irr_table[at + 3u] = 0u;
            irr_table[at + 4u] = 0u;
            irr_table[at + 5u] = 0u;
            irr_table[at + 6u] = 0u;
            return;
        }
    }
}

@compute @workgroup_size(1)
fn irradiance_args() {
    let n = min(atomicLoad(&irr_requests[IRR_COUNT]), irr.max_requests);
    irr_args[0] = (n + 63u) / 64u;
    irr_args[1] = 1u;
    irr_args[2] = 1u;
}

@compute @workgroup_size(64)
fn irradiance_update(@builtin(global_invocation_id) gid: vec3<u32>) {
    let n = min(atomicLoad(&irr_requests[IRR_COUNT]), irr.max_requests);
    if gid.x >= n {
        return;
    }
    let slot = atomicLoad(&irr_requests[IRR_LIST + gid.x]);
    let at = slot * IRR_WORDS;
    let key = vec2<u32>(irr_table[at], irr_table[at + 1u]);
    let count = irr_table[at + 3u];
    // The budget goes first to entries with no samples, then evenly to the rest; whether
    // an entry is refreshed depends on its key and the frame only, never on the order of
    // the list.
    let fresh = min(atomicLoad(&irr_requests[IRR_FRESH]), n);
    var share = f32(irr.budget) / f32(max(fresh, 1u));
    if count != 0u {
        share = f32(irr.budget - min(irr.budget, fresh)) / f32(max(n - fresh, 1u));
    }
    let stream = irr_stream(key);
    if f32(pcg_hash(stream ^ pcg_hash(irr.stamp)) >> 8u) * (1.0 / 16777216.0) >= share {
        return;
    }
    let taken = irr_table[at + 7u];
    // The direction's R2 offsets, drawn once per entry (CpuIrradiance::sample).
    let offsets = rng_new(irr.seed, stream, 0xFFFFFFFFu);
    let offset = vec2<u32>(pcg_hash(offsets), pcg_hash(pcg_hash(offsets)));
    var rng = rng_new(irr.seed, stream, taken);
    // A point uniform on the face, just off it (FaceKey::point).
    let face = (key.y >> 16u) & 7u;
    let axis = face / 2u;
    let up = face % 2u == 0u;
    var normal = vec3<f32>(0.0);
    normal[axis] = select(-1.0, 1.0, up);
    var p = vec3<f32>(0.0);
    p[axis] = select(-SURFACE_OFFSET, 1.0 + SURFACE_OFFSET, up);
    p[(axis + 1u) % 3u] = rng_next(&rng);
    p[(axis + 2u) % 3u] = rng_next(&rng);
    let base = ray_new(irr_voxel(at), vec3<f32>(0.0), normal);
    var e = vec3<f32>(sun_sample(base, p, normal, &rng).irradiance);
    let u = vec2<f32>((taken * IRR_R2 + offset) >> vec2<u32>(8u)) * (1.0 / 16777216.0);
    let w = sample_cosine(normal, u);
    e += PI * path_radiance(ray_at(base, p, w), 1u, false, &rng).radiance;
    var sum = vec3<f32>(bitcast<f32>(irr_table[at + 4u]), bitcast<f32>(irr_table[at + 5u]), bitcast<f32>(irr_table[at + 6u])) + e;
    var c = count + 1u;
    if c >= IRR_HISTORY {
        sum *= 0.5;
        c = IRR_HISTORY / 2u;
    }
    irr_table[at + 3u] = c;
    irr_table[at + 4u] = bitcast<u32>(sum.x);
    irr_table[at + 5u] = bitcast<u32>(sum.y);
    irr_table[at + 6u] = bitcast<u32>(sum.z);
    irr_table[at + 7u] = taken + 1u;
    atomicAdd(&irr_requests[IRR_TAKEN], 1u);
}

const IRR_WORDS: u32 = 8u;
const IRR_PROBES: u32 = 64u;
const IRR_NONE: u32 = 4294967295u;
const IRR_HISTORY: u32 = 64u;
const IRR_COUNT: u32 = 0u;
const IRR_FRESH: u32 = 1u;
const IRR_TAKEN: u32 = 2u;
const IRR_OCCUPIED: u32 = 3u;
const IRR_LIST: u32 = 4u;
const IRR_R2 = vec2<u32>(3242174889u, 2447445414u);
struct IrradianceInfo {
    // This frame's stamp (from 1): an entry requested this frame holds it.
    stamp: u32,
    // Slots of the table less one (a power of two less one).
    mask: u32,
    // Room in the request list, in slots.
    max_requests: u32,
    // Entry samples the frame's ray budget pays for.
    budget: u32,
    // Seed of the entries' sample streams.
    seed: u32,
    // Boxes in the invalidation list.
    boxes: u32,
    // Padding to 16 bytes.
    _pad0: u32,
    // Padding to 16 bytes.
    _pad1: u32,
}
`,Tl=lc[nc.fields.sun_on.offset/4]!==0,El=Math.max(1,Math.floor(Y.DEFAULT_RAYS/(Tl?Y.RAYS_PER_SAMPLE_SUN:Y.RAYS_PER_SAMPLE)));function Dl(e){let t=Y.MIN_SLOTS;for(;t<2*e;)t*=2;return t}function Ol(e,t){let n=Y.BOUNCE_DISTANCE,r=t=>[t%e[0],Math.floor(t/e[0])%e[1],Math.floor(t/(e[0]*e[1]))],i=e=>{let n=new Map;for(let i of t){let t=r(i).map(t=>Math.floor(t/e));n.set(t.join(`,`),t)}return[...n.values()].sort((e,t)=>e[0]-t[0]||e[1]-t[1]||e[2]-t[2])},a=(e,t)=>{let r=16*t;return e.flatMap(e=>{let t=e.map(e=>e*r-n),i=e.map(e=>e*r+r-1+n);return[[t[0],t[1],t[2],0],[i[0],i[1],i[2],0]]})},o=i(1);if(o.length<=Y.MAX_BOXES)return new Int32Array(a(o,1).flat());let s=i(4);if(s.length<=Y.MAX_BOXES)return new Int32Array(a(s,4).flat());let c=[1/0,1/0,1/0],l=[-1/0,-1/0,-1/0];for(let e of t){let t=r(e);for(let e=0;e<3;e++)c[e]=Math.min(c[e],t[e]*16-n),l[e]=Math.max(l[e],t[e]*16+15+n)}return new Int32Array([c[0],c[1],c[2],0,l[0],l[1],l[2],0])}var kl=class{device;world;sample;sampleLayout;invalidate;invalidateLayout;update;updateLayout;args;argsLayout;light;info;invalidateInfo;noBoxes;counters;cache;sums;stats=null;constructor(e,t){this.device=e,this.world=t,{pipeline:this.sample,layout:this.sampleLayout}=bc(e,t,`irradiance.wgsl`,Cl,`path_trace`,[`uniform`,`uniform`,`storage`,`uniform`,`storage`,`storage`]);let n=[`uniform`,`uniform`,`storage`,`storage`,`read-only-storage`],r=(n,r)=>bc(e,t,`irradiance_update.wgsl`,wl,n,r);({pipeline:this.invalidate,layout:this.invalidateLayout}=r(`irradiance_invalidate`,n)),{pipeline:this.update,layout:this.updateLayout}=r(`irradiance_update`,n),{pipeline:this.args,layout:this.argsLayout}=r(`irradiance_args`,[...n,`storage`]);let i=t=>e.createBuffer({size:t,usage:GPUBufferUsage.UNIFORM|GPUBufferUsage.COPY_DST});this.light=i(lc.length*4),e.queue.writeBuffer(this.light,0,new Uint32Array(lc)),this.info=i(sc.size),this.invalidateInfo=i(sc.size),this.noBoxes=e.createBuffer({label:`irradiance no boxes`,size:32,usage:GPUBufferUsage.STORAGE}),this.counters=e.createBuffer({label:`irradiance counters`,size:Y.LIST*4,usage:GPUBufferUsage.MAP_READ|GPUBufferUsage.COPY_DST}),this.sums=new fl(e,`irradiance`)}get samples(){return this.sums.samples}allocate(e,t,n,r){this.drop();let i=GPUBufferUsage.STORAGE|GPUBufferUsage.COPY_SRC|GPUBufferUsage.COPY_DST;return{size:e,slots:t,table:this.device.createBuffer({label:`irradiance table`,size:t*Y.WORDS*4,usage:i}),requests:this.device.createBuffer({label:`irradiance requests`,size:(Y.LIST+Math.min(t,Y.MAX_REQUESTS))*4,usage:i}),args:this.device.createBuffer({label:`irradiance dispatch`,size:16,usage:GPUBufferUsage.STORAGE|GPUBufferUsage.INDIRECT}),generation:n,stamp:r,keyed:0}}drop(){if(this.cache){for(let e of[this.cache.table,this.cache.requests,this.cache.args])e.destroy();this.cache=void 0}}infoBytes(e,t){return gc(sc,{stamp:e.stamp,mask:e.slots-1,max_requests:Math.min(e.slots,Y.MAX_REQUESTS),budget:El,seed:0,boxes:t})}async prepare(e,t){let n=JSON.stringify(e.chunks),r=Dl(t),i=Math.min(this.device.limits.maxStorageBufferBindingSize,this.device.limits.maxBufferSize);if(r*Y.WORDS*4>i)throw Error(`an irradiance cache for ${t} pixels needs ${r*Y.WORDS*4} bytes, over this adapter's ${i}-byte binding`);let a=this.cache;(!a||a.size!==n||a.slots<r||a.generation>e.generation)&&(a=this.cache=this.allocate(n,r,e.generation,0)),a.keyed>a.slots/2&&(a=this.cache=this.allocate(n,a.slots,a.generation,a.stamp));let o=e.changesSince(a.generation);if(a.generation=e.generation,a.stamp+=1,o===`everything`)return a=this.cache=this.allocate(n,a.slots,e.generation,a.stamp),a;if(this.device.queue.writeBuffer(a.requests,0,new Uint32Array(3)),o.length===0)return a;let s=Ol(e.chunks,o),c=this.device.createBuffer({label:`irradiance boxes`,size:s.byteLength,usage:GPUBufferUsage.STORAGE|GPUBufferUsage.COPY_DST});this.device.queue.writeBuffer(c,0,s),this.device.queue.writeBuffer(this.invalidateInfo,0,this.infoBytes(a,s.length/8));let l=xc(this.device,this.invalidateLayout,[this.light,this.invalidateInfo,a.table,a.requests,c]);return await Sc(this.device,this.invalidate(e.hasInstances),this.world.of(e),l,Math.ceil(a.slots/64)),c.destroy(),a}async render(e,t,n,r){e.trackChanges();let i=await this.prepare(e,n*r),a=this.sums.next(e,t,n,r);this.device.queue.writeBuffer(this.info,0,this.infoBytes(i,0));let o=[this.light,this.info,i.table,i.requests,this.noBoxes,i.args],s=xc(this.device,this.sampleLayout,[this.sums.frame,this.light,a,this.info,i.table,i.requests]),c=this.world.of(e),l=await Cc(this.device,this.sample(e.hasInstances),c,s,n,r),[u,d]=await Promise.all([this.args(e.hasInstances),this.update(e.hasInstances)]),f=l.beginComputePass({label:`irradiance_args`});f.setPipeline(u),f.setBindGroup(0,c),f.setBindGroup(1,xc(this.device,this.argsLayout,o)),f.dispatchWorkgroups(1),f.end(),f=l.beginComputePass({label:`irradiance_update`}),f.setPipeline(d),f.setBindGroup(0,c),f.setBindGroup(1,xc(this.device,this.updateLayout,o.slice(0,5))),f.dispatchWorkgroupsIndirect(i.args,0),f.end(),l.copyBufferToBuffer(i.requests,0,this.counters,0,Y.LIST*4);let p=await this.sums.finish(l,n,r);await this.counters.mapAsync(GPUMapMode.READ);let m=new Uint32Array(this.counters.getMappedRange().slice(0));return this.counters.unmap(),i.keyed=m[Y.OCCUPIED],this.stats={requested:m[Y.COUNT],fresh:m[Y.FRESH],samples:m[Y.TAKEN],keyed:m[Y.OCCUPIED],slots:i.slots,stamp:i.stamp},p}},Al=class extends Error{};async function jl(){if(!(`gpu`in navigator)||!navigator.gpu)throw new Al(`this browser has no WebGPU`);let e=await navigator.gpu.requestAdapter();if(!e)throw new Al(`this browser offers WebGPU but no adapter`);let t=await e.requestDevice({requiredLimits:{maxStorageBufferBindingSize:e.limits.maxStorageBufferBindingSize,maxBufferSize:e.limits.maxBufferSize}});return t.addEventListener(`uncapturederror`,e=>console.error(`WebGPU: ${e.error.message}`)),t.lost.then(e=>console.error(`WebGPU device lost: ${e.message}`)),{device:t,fallback:(e.info?.isFallbackAdapter??!1)||/swiftshader/i.test(e.info?.description??``)}}var Ml=class{device;buffer;info;offsets;regions=[];hierarchy=new Uint8Array;generation=0;layoutGeneration=0;chunks=[0,0,0];instanceSlots=0;mirror;locals=[];instanceHierarchy=new Kc;localRecords=new Uint32Array;prints;log=[];logFrom=0;constructor(e){this.device=e;let t=(t,n)=>e.createBuffer({label:t,size:n,usage:GPUBufferUsage.UNIFORM|GPUBufferUsage.COPY_DST});this.info=t(`world_info`,$s.size),this.offsets=t(`world_offsets`,32)}get hasInstances(){return this.instanceSlots>0}uploadAll(e,t){let n=this.localData(e);this.hierarchy=t??this.hierarchyOf(e,n.records);let r=[...Qs.map(t=>this.usedBytes(e,t.id,n)),this.hierarchy.length],i=0;this.regions=r.map(e=>{let t=Math.ceil((e*1.25+65536)/256)*256,n={at:i,capacity:t};return i+=t,n});let a=this.device.limits.maxStorageBufferBindingSize;if(i>a)throw new Al(`the world needs ${i} bytes in one binding; this adapter allows ${a}`);this.buffer?.destroy(),this.buffer=this.device.createBuffer({label:`world`,size:Math.max(i,16),usage:GPUBufferUsage.STORAGE|GPUBufferUsage.COPY_DST}),Qs.forEach((t,n)=>this.write(n,0,e.bytes(t.id))),this.writeLocals(e,n),this.write(Fl,0,this.hierarchy);let o=new Uint32Array(8);this.regions.forEach((e,t)=>o[t]=e.at/4),this.device.queue.writeBuffer(this.offsets,0,o),this.writeInfo(e),this.layoutGeneration+=1,this.generation+=1,this.mirror=e,this.prints&&(this.prints=new el(e),this.note(`everything`))}update(e,t,n){let r=e=>Qs.findIndex(t=>t.id===e),i=n||t.some(e=>e.id===Nl||e.id===Pl),a=this.locals.length>0&&i?this.localData(e):void 0,o=t.some(e=>e.id===Pl)||a!==void 0,s=o?this.hierarchyOf(e,a?.records??this.localRecords):this.hierarchy;if((n||a)&&Qs.some((t,n)=>this.usedBytes(e,t.id,a)>this.regions[n].capacity)||s.length>this.regions[Fl].capacity)this.uploadAll(e,s);else{for(let n of t){let t=r(n.id);if(t<0)continue;let i=n.lo&-4,a=e.bytes(n.id),o=Math.min(a.length,n.hi+3&-4);this.write(t,i,a.subarray(i,o))}a&&this.writeLocals(e,a),o&&(this.hierarchy=s,this.write(Fl,0,s)),(n||a)&&this.writeInfo(e),this.generation+=1,this.prints&&this.note(this.prints.update(e,t))}}setLocals(e){if(JSON.stringify(e)===JSON.stringify(this.locals))return;let t=this.localRecords;this.locals=e.map(e=>({min:[...e.min],size:[...e.size],material:e.material}));let n=this.mirror;if(!n)return;let r=this.localData(n),i=this.hierarchyOf(n,r.records);if(Qs.some((e,t)=>this.usedBytes(n,e.id,r)>this.regions[t].capacity)||i.length>this.regions[Fl].capacity)this.uploadAll(n,i);else if(this.writeLocals(n,r),this.hierarchy=i,this.write(Fl,0,i),this.writeInfo(n),this.generation+=1,this.prints){let e=new Set;for(let n of[t,r.records])for(let t=0;t<n.length/Oc;t++){let r=jc(n,t);if(r)for(let t of $c(r,this.chunks))e.add(t)}this.note([...e].sort((e,t)=>e-t))}}localData(e){let t=Math.ceil(e.bytes(Nl).length/4/mc.TYPE_ALIGN)*mc.TYPE_ALIGN;return{typeBase:t,...kc(this.locals,t)}}usedBytes(e,t,n){let r=e.bytes(t).length;return n?t===Nl?n.types.length>0?4*n.typeBase+n.types.byteLength:r:t===Pl?r+n.records.byteLength:r:r}writeLocals(e,t){let n=e=>new Uint8Array(e.buffer,e.byteOffset,e.byteLength),r=e=>Qs.findIndex(t=>t.id===e);this.write(r(Nl),4*t.typeBase,n(t.types)),this.write(r(Pl),e.bytes(Pl).length,n(t.records)),this.localRecords=t.records}hierarchyOf(e,t){let n=e.words(Pl);if(t&&t.length>0){let e=new Uint32Array(n.length+t.length);e.set(n),e.set(t,n.length),n=e}let r=this.instanceHierarchy.update(n);return new Uint8Array(r.buffer,r.byteOffset,r.byteLength)}trackChanges(){!this.prints&&this.mirror&&(this.prints=new el(this.mirror),this.log=[],this.logFrom=this.generation)}changesSince(e){if(e<this.logFrom)return`everything`;let t=new Set;for(let n of this.log)if(!(n.generation<=e)){if(n.changes===`everything`)return`everything`;for(let e of n.changes)t.add(e)}return[...t].sort((e,t)=>e-t)}note(e){this.log.push({generation:this.generation,changes:e}),this.log.length>64&&(this.logFrom=this.log.shift().generation)}write(e,t,n){if(n.length===0)return;let r=n.length%4==0?n:(()=>{let e=new Uint8Array(n.length+3&-4);return e.set(n),e})();this.device.queue.writeBuffer(this.buffer,this.regions[e].at+t,r)}writeInfo(e){let[t,n,r]=e.size,i=(e.bytes(Pl).length/4+this.localRecords.length)/Oc;this.instanceSlots=i,this.chunks=[Math.ceil(t/16),Math.ceil(n/16),Math.ceil(r/16)],this.device.queue.writeBuffer(this.info,0,gc($s,{size:[t,n,r],instance_slots:i,chunks:this.chunks,max_steps:fc}))}},Nl=6,Pl=7,Fl=Qs.length,Il=class{device;world;compute;group1;view;gbuffer;pixels;staging;width=0;height=0;constructor(e,t){this.device=e,this.world=t,{pipeline:this.compute,layout:this.group1}=bc(e,t,`render.wgsl`,Zs,`render`,[`uniform`,`storage`,`storage`]),this.view=e.createBuffer({size:ec.size,usage:GPUBufferUsage.UNIFORM|GPUBufferUsage.COPY_DST}),this.gbuffer=e.createBuffer({size:16,usage:GPUBufferUsage.STORAGE})}async render(e,t,n,r,i){let a=this.device,o=n*r*4;n===this.width&&r===this.height&&this.pixels||(this.pixels?.destroy(),this.staging?.destroy(),this.pixels=a.createBuffer({label:`pixels`,size:o,usage:GPUBufferUsage.STORAGE|GPUBufferUsage.COPY_SRC}),this.staging=a.createBuffer({label:`frame`,size:o,usage:GPUBufferUsage.MAP_READ|GPUBufferUsage.COPY_DST}),this.width=n,this.height=r);let s=Io(t,n,r),c=uc[i];if(c===void 0)throw Error(`the render pass has no mode ${i}`);a.queue.writeBuffer(this.view,0,gc(ec,{cam_oi:s.int,mode:c,cam_of:s.frac,width:n,forward:s.forward,height:r,right:s.right,flags:0,up:s.up,steps_scale:Math.fround(1/Math.log2(513)),sun:dc}));let l=a.createBindGroup({layout:this.group1,entries:[{binding:0,resource:{buffer:this.view}},{binding:1,resource:{buffer:this.pixels}},{binding:2,resource:{buffer:this.gbuffer}}]}),u=await Cc(a,this.compute(e.hasInstances),this.world.of(e),l,n,r),d=new Uint8ClampedArray(await wc(a,u,this.pixels,0,this.staging,o));return new ImageData(d,n,r)}},Ll=class{device;world;pipeline;group1;light;sums;constructor(e,t){this.device=e,this.world=t,{pipeline:this.pipeline,layout:this.group1}=bc(e,t,`pathtrace.wgsl`,Xs,`path_trace`,[`uniform`,`uniform`,`storage`]),this.light=e.createBuffer({size:cc.length*4,usage:GPUBufferUsage.UNIFORM|GPUBufferUsage.COPY_DST}),e.queue.writeBuffer(this.light,0,new Uint32Array(cc)),this.sums=new fl(e,`path`)}get samples(){return this.sums.samples}async render(e,t,n,r){let i=this.sums.next(e,t,n,r),a=xc(this.device,this.group1,[this.sums.frame,this.light,i]),o=await Cc(this.device,this.pipeline(e.hasInstances),this.world.of(e),a,n,r);return this.sums.finish(o,n,r)}},Rl=class{device;world;frames;paths;gi;roma;irradiance;last;constructor(e,t){this.device=e,this.world=new vc(e),this.pass(t)}pass(e){return e===`pathtrace`?this.paths??=new Ll(this.device,this.world):e===`gi`?this.gi??=new ll(this.device,this.world):e===`roma`?this.roma??=new Sl(this.device,this.world):e===`irradiance`?this.irradiance??=new kl(this.device,this.world):this.frames??=new Il(this.device,this.world)}static accumulates(e){return e===`pathtrace`||e===`gi`||e===`roma`||e===`irradiance`}samples(e){return e===`gi`?this.gi?.still??0:e===`roma`?this.roma?.samples??0:e===`irradiance`?this.irradiance?.samples??0:e===`pathtrace`?this.paths?.samples??0:0}get irradianceStats(){return this.irradiance?.stats??null}async render(e,t,n,r,i){let a=this.pass(i);return this.last=a instanceof Il?await a.render(e,t,n,r,i):await a.render(e,t,n,r),this.last}};function zl(e){let t=e.filter(e=>e.kind===0||e.kind===2);return(t.length>0?t:e).map(e=>e.id)}function Bl(e,t){if(t.length!==0)return t[Number(BigInt.asUintN(64,e)%BigInt(t.length))]}function Vl(e){return e.length===3&&e.every(e=>Number.isFinite(e)&&Math.abs(e)<1e15)}function Hl(e,t,n,r){if(!Vl(e))return;let i=Ul(e),a=i.map(e=>Math.max(0,e)),o=i.map((e,n)=>Math.min(t[n],e+3));if(!a.some((e,t)=>e>=o[t])&&!(r&&r.every((e,t)=>e>=a[t]&&e<o[t])))return{min:a,size:o.map((e,t)=>e-a[t]),material:n}}function Ul(e){return e.map(e=>Math.floor(e)-1)}function Wl(e){let[t,n,r]=Ul(e);return[t+1.5,n+3,r+1.5]}function Gl(e,t,n,r){let i=[];for(let a of[...e].sort((e,t)=>e.session<t.session?-1:+(e.session>t.session))){let e=Bl(a.session,n),o=e===void 0?void 0:Hl(a.position,t,e,r);o&&i.push(o)}return i}function Kl(e,t,n,r){let i=Fo(e),a=r.map((t,n)=>t-e.pos[n]),o=(e,t)=>e[0]*t[0]+e[1]*t[1]+e[2]*t[2],s=o(a,i.forward);if(s<=.001)return;let c=Math.tan(e.fov_y*Math.PI/360),l=o(a,i.right)/(s*c*(t/n)),u=o(a,i.up)/(s*c);return[(l+1)/2*t,(1-u)/2*n]}function ql(e,t,n,r,i){let a=Fo(e),o=Math.tan(e.fov_y*Math.PI/360),s=(2*r/t-1)*o*(t/n),c=(1-2*i/n)*o;return[0,1,2].map(e=>a.forward[e]+s*a.right[e]+c*a.up[e])}function Jl(e,t,n,r,i){let{width:a,height:o}=e.canvas,s=e=>[e&1?r[0]:n[0],e&2?r[1]:n[1],e&4?r[2]:n[2]];e.strokeStyle=i,e.lineWidth=2,e.beginPath();for(let n=0;n<8;n++)for(let r of[1,2,4]){if(n&r)continue;let i=Kl(t,a,o,s(n)),c=Kl(t,a,o,s(n|r));i&&c&&(e.moveTo(i[0],i[1]),e.lineTo(c[0],c[1]))}e.stroke()}function Yl(e,t,n,r){let{width:i,height:a}=e.canvas;e.clearRect(0,0,i,a),n&&Jl(e,t,n.min,n.max,n.refusal?`#f44`:`#ff0`);let o=[];e.font=`${Math.max(11,Math.round(a/40))}px system-ui, sans-serif`;for(let n of r){let r=n.name||n.user||`anonymous`;if(n.pointer.length===3){let r=n.pointer.map(Number);Jl(e,t,r,[r[0]+1,r[1]+1,r[2]+1],`#0ff`)}if(!Vl(n.position))continue;let s=Kl(t,i,a,Wl(n.position));if(!s||!(s[0]>=0&&s[1]>=0&&s[0]<i&&s[1]<a))continue;let c=Kl(t,i,a,n.position)??s;e.fillStyle=`#fff`,e.textAlign=`center`,e.textBaseline=`bottom`,e.fillText(r,s[0],s[1]-2),o.push({name:r,x:c[0],y:c[1]})}return o}var Xl=class{chunks;blocks;voxels;size;dims;constructor(e){this.chunks=e.words(0),this.blocks=e.words(2),this.voxels=e.words(3),this.size=e.size,this.dims=[e.size[0]>>4,e.size[1]>>4,e.size[2]>>4]}inside(e,t,n){return e>=0&&t>=0&&n>=0&&e<this.size[0]&&t<this.size[1]&&n<this.size[2]}cell(e,t,n){let[r,i,a]=[e>>4,t>>4,n>>4],o=this.chunks[r+this.dims[0]*(i+this.dims[1]*a)],s=Dc(o);if(s===0)return{material:0,edge:16};if(s===1)return{material:o&Tc,edge:16};let c=this.blocks[(o&Ec)+((e>>2&3)+4*(t>>2&3)+16*(n>>2&3))],l=Dc(c);if(l===0)return{material:0,edge:4};if(l===1)return{material:c&Tc,edge:4};let u=(e&3)+4*(t&3)+16*(n&3),d=this.voxels[(c&Ec)+(u>>1)],f=u&1?d>>>16:d&65535;return{material:f&32768?f&Tc:0,edge:1}}};function Zl(e,t,n,r=4096){let i=0,a=r;for(let r=0;r<3;r++){if(n[r]===0){if(t[r]<0||t[r]>=e.size[r])return;continue}let o=(0-t[r])/n[r],s=(e.size[r]-t[r])/n[r];i=Math.max(i,Math.min(o,s)),a=Math.min(a,Math.max(o,s))}if(i>a)return;let o=1e-7,s;for(;i<=a;){let r=t.map((e,t)=>e+n[t]*(i+o)).map(Math.floor);if(!e.inside(r[0],r[1],r[2]))return;let a=e.cell(r[0],r[1],r[2]);if(a.material!==0)return{voxel:r,before:s??r,material:a.material};s=r;let c=1/0;for(let e=0;e<3;e++){if(n[e]===0)continue;let i=Math.floor(r[e]/a.edge)*a.edge,o=n[e]>0?i+a.edge:i;c=Math.min(c,(o-t[e])/n[e])}s=t.map((e,t)=>e+n[t]*(c-o)).map(Math.floor),i=Math.max(c,i+o)}}function Ql(){try{new Headers}catch{throw Error(`connect-web requires the fetch API. Are you running on an old version of Node.js?`)}}function $l(e,t){let n=oo(e);if(n)throw t.forEach((e,t)=>{n.metadata.append(t,e)}),n;if(!t.has(`Grpc-Status`)&&!e.has(`Grpc-Status`))throw new B(`protocol error: missing status`,z.Internal)}function eu(e,t,n,r){let i=new Headers(n??{});i.set(Ya,e?no:ro),i.set(to,`1`);let a=i.get(`User-Agent`)??i.get(`X-User-Agent`)??`connect-es/2.3.0`;return i.set(eo,a),r&&i.set($a,a),t!==void 0&&i.set(Xa,`${t}m`),i}function tu(e){switch(e){case 400:return z.Internal;case 401:return z.Unauthenticated;case 403:return z.PermissionDenied;case 404:return z.Unimplemented;case 429:case 502:case 503:case 504:return z.Unavailable;default:return z.Unknown}}function nu(e,t){if(e>=200&&e<300)return{foundStatus:t.has(Za),headerError:oo(t)};throw new B(decodeURIComponent(t.get(`Grpc-Message`)??`HTTP ${e}`),tu(e),t)}var ru=function(e){return this instanceof ru?(this.v=e,this):new ru(e)},iu=function(e,t,n){if(!Symbol.asyncIterator)throw TypeError(`Symbol.asyncIterator is not defined.`);var r=n.apply(e,t||[]),i,a=[];return i=Object.create((typeof AsyncIterator==`function`?AsyncIterator:Object).prototype),s(`next`),s(`throw`),s(`return`,o),i[Symbol.asyncIterator]=function(){return this},i;function o(e){return function(t){return Promise.resolve(t).then(e,d)}}function s(e,t){r[e]&&(i[e]=function(t){return new Promise(function(n,r){a.push([e,t,n,r])>1||c(e,t)})},t&&(i[e]=t(i[e])))}function c(e,t){try{l(r[e](t))}catch(e){f(a[0][3],e)}}function l(e){e.value instanceof ru?Promise.resolve(e.value.v).then(u,d):f(a[0][2],e)}function u(e){c(`next`,e)}function d(e){c(`throw`,e)}function f(e,t){e(t),a.shift(),a.length&&c(a[0][0],a[0][1])}},au={redirect:`error`};function ou(e){Ql();let t=e.useBinaryFormat??!0;return{async unary(n,r,i,a,o,s){let{serialize:c,parse:l}=po(n,t,e.jsonOptions,e.binaryOptions);return i=i===void 0?e.defaultTimeoutMs:i<=0?void 0:i,await go({interceptors:e.interceptors,signal:r,timeoutMs:i,req:{stream:!1,service:n.parent,method:n,requestMethod:`POST`,url:so(e.baseUrl,n),header:eu(t,i,a,!1),contextValues:s??qa(),message:o},next:async t=>{let r=await(e.fetch??globalThis.fetch)(t.url,Object.assign(Object.assign({},au),{method:t.requestMethod,headers:t.header,signal:t.signal,body:Oa(0,c(t.message))})),{headerError:i}=nu(r.status,r.headers);if(!r.body)throw i===void 0?`missing response body`:i;let a=Da(r.body).getReader(),o,s;for(;;){let e=await a.read();if(e.done)break;let{flags:t,data:n}=e.value;if((t&1)==1)throw new B(`protocol error: received unsupported compressed output`,z.Internal);if(t===128){if(o!==void 0)throw`extra trailer`;o=Ja(n)}else{if(s!==void 0)throw new B(`extra message`,z.Unimplemented);s=l(n)}}if(o===void 0)throw i===void 0?new B(`missing trailer`,r.headers.has(`Grpc-Status`)?z.Unimplemented:z.Unknown):i;if($l(o,r.headers),s===void 0)throw new B(`missing message`,o.has(`Grpc-Status`)?z.Unimplemented:z.Unknown);return{stream:!1,service:n.parent,method:n,header:r.headers,message:s,trailer:o}}})},async stream(n,r,i,a,o,s){let{serialize:c,parse:l}=po(n,t,e.jsonOptions,e.binaryOptions);function u(e,t,n,r,i){return iu(this,arguments,function*(){let i=Da(e).getReader();if(t){if(!(yield ru(i.read())).done)throw`extra data for trailers-only`;return yield ru(void 0)}let a=!1;for(;;){let e=yield ru(i.read());if(e.done)break;let{flags:t,data:o}=e.value;if((t&128)==128){if(a)throw`extra trailer`;a=!0;let e=Ja(o);$l(e,r),e.forEach((e,t)=>n.set(t,e))}else{if(a)throw`extra message`;yield yield ru(l(o))}}if(!a)throw`missing trailer`})}async function d(e){if(n.methodKind!=`server_streaming`)throw`The fetch API does not support streaming request bodies`;let t=await e[Symbol.asyncIterator]().next();if(t.done==1)throw`missing request message`;return Oa(0,c(t.value))}return i=i===void 0?e.defaultTimeoutMs:i<=0?void 0:i,_o({interceptors:e.interceptors,signal:r,timeoutMs:i,req:{stream:!0,service:n.parent,method:n,requestMethod:`POST`,url:so(e.baseUrl,n),header:eu(t,i,a,!1),contextValues:s??qa(),message:o},next:async t=>{let n=await(e.fetch??globalThis.fetch)(t.url,Object.assign(Object.assign({},au),{method:t.requestMethod,headers:t.header,signal:t.signal,body:await d(t.message)})),{foundStatus:r,headerError:i}=nu(n.status,n.headers);if(i!=null)throw i;if(!n.body)throw`missing response body`;let a=new Headers;return Object.assign(Object.assign({},t),{header:n.headers,trailer:a,message:u(n.body,r,a,n.headers,t.signal)})}})}}}var su=`naadf.token`,cu=100,lu=5e3,uu=class e{events;cache;mirror=new Hs;client;bytesReceived=0;snapshotBytes=0;abort;stopped=!1;saving;constructor(e,t){this.events=e,this.cache=t,this.client=Ra(Do,ou({baseUrl:location.origin,useBinaryFormat:!0}))}static token(){return sessionStorage.getItem(su)}setToken(e){sessionStorage.setItem(su,e),this.restart()}callOptions(){let t=e.token();return{headers:t?{authorization:`Bearer ${t}`}:{}}}async whoAmI(){return this.client.status({},this.callOptions())}async restore(){return!this.cache||!await this.cache.restore(this.mirror).catch(()=>!1)?!1:(this.events.restored(this.mirror),!0)}saveSoon(){this.cache&&!this.saving&&(this.saving=setTimeout(()=>{this.saving=void 0,this.cache?.save(this.mirror).catch(e=>console.warn(`the page cache: ${e}`))},1e3))}async run(){let e=cu,t=!0;for(;!this.stopped;){this.events.state(t?`connecting`:`reconnecting`),t=!1,this.abort=new AbortController;try{await this.follow(this.abort.signal)&&(e=cu)}catch(e){if(e instanceof G)console.warn(e.message);else{let t=B.from(e);if(t.code===z.Unauthenticated||t.code===z.PermissionDenied){this.events.state(`need-token`,t.rawMessage);return}if(t.code===z.FailedPrecondition){this.events.state(`error`,t.rawMessage);return}if(t.code===z.Canceled&&this.stopped)return;t.code!==z.Canceled&&console.warn(`the world stream ended: ${t.message}`)}}if(this.stopped)return;this.events.state(`reconnecting`);let n=e*(1+Math.random()/4);e=Math.min(lu,e*2),await new Promise(e=>setTimeout(e,n))}}restart(){this.abort?.abort()}async follow(e){let t=this.mirror,n=N(bo,{protocolVersion:2,cached:t.cached(),resume:t.holdsWorld?{version:t.version,digest:t.digest}:void 0,deltaForm:Eo.PATCH,presence:!0}),r=!1;this.events.joined();for await(let i of this.client.join(n,{...this.callOptions(),signal:e})){r=!0;let e=pu(i);this.bytesReceived+=e;let n=i.kind;switch(n.case===`header`&&(this.snapshotBytes=0),(n.case===`header`||n.case===`page`)&&(this.snapshotBytes+=e),n.case){case`header`:this.events.state(`syncing`),t.header(n.value)||this.live(n.value.resume);break;case`page`:t.page(n.value)&&this.live(!1);break;case`delta`:{let{touched:e,resized:r}=t.delta(n.value);this.events.patched(t,e,r),this.saveSoon();break}case`presence`:this.events.presence(n.value.entries)}}return r}live(e){e||this.events.snapshot(this.mirror),this.saveSoon(),this.events.state(`live`)}},du=e=>e<128?1:e<16384?2:e<2097152?3:e<268435456?4:5,fu=e=>1+du(e)+e;function pu(e){if(e.kind.case!==`page`)return kr(xo,e).length;let t=e.kind.value,n=t.indices.reduce((e,t)=>e+du(t),0);return fu((t.buffer?1+du(t.buffer):0)+(t.indices.length?fu(n):0)+(t.zstd.length?fu(t.zstd.length):0))}var mu=[`voxel`,`erase`,`box`,`sphere`,`paint`,`flood`],hu=65536,gu=(e,t)=>[e[0]+t,e[1]+t,e[2]+t],_u=e=>[e[0]+.5,e[1]+.5,e[2]+.5];function vu(e,t){return{min:e.map(e=>Math.floor(e-t-.5)+1),max:e.map(e=>Math.ceil(e+t-.5))}}function yu(e,t){return{min:e.map((e,n)=>Math.min(e,t[n])),max:e.map((e,n)=>Math.max(e,t[n])+1)}}function bu(e,t,n){let r=e.cell(t[0],t[1],t[2]).material;if(r===n)return{min:t,max:gu(t,1),refusal:`already that material`};let i=new Set,a=t=>t[0]+e.size[0]*(t[1]+e.size[1]*t[2]),o=[t];i.add(a(t));let s=[...t],c=gu(t,1);for(;o.length;){let t=o.pop();for(let e=0;e<3;e++)s[e]=Math.min(s[e],t[e]),c[e]=Math.max(c[e],t[e]+1);for(let[n,l,u]of[[1,0,0],[-1,0,0],[0,1,0],[0,-1,0],[0,0,1],[0,0,-1]]){let d=[t[0]+n,t[1]+l,t[2]+u];if(e.inside(d[0],d[1],d[2])&&!i.has(a(d))&&e.cell(d[0],d[1],d[2]).material===r){if(i.size>=65536)return{min:s,max:c,refusal:`more than ${hu} voxels`};i.add(a(d)),o.push(d)}}}return{min:s,max:c}}function xu(e,t,n){switch(e.tool){case`voxel`:return{min:n.before,max:gu(n.before,1)};case`erase`:return{min:n.voxel,max:gu(n.voxel,1)};case`box`:return yu(e.anchor??n.before,n.before);case`sphere`:return vu(_u(n.before),e.radius);case`paint`:return vu(_u(n.voxel),e.radius);case`flood`:return bu(t,n.voxel,e.material)}}function Su(e,t){if(!t||t.refusal||e.tool!==`voxel`&&e.tool!==`box`)return[];let n=t.max.map((e,n)=>e-t.min[n]);return n.some(e=>e<1||e>127)||t.min.some(e=>e<0)?[]:[{min:[...t.min],size:n,material:e.material}]}function Cu(e,t){let n=e.material;switch(e.tool){case`voxel`:return JSON.stringify({op:`set`,voxels:[[...t.before,n]]});case`erase`:return JSON.stringify({op:`set`,voxels:[[...t.voxel,0]]});case`box`:{if(!e.anchor){e.anchor=t.before;return}let r=yu(e.anchor,t.before);return e.anchor=void 0,JSON.stringify({op:`box`,min:r.min,max:r.max,material:n})}case`sphere`:return JSON.stringify({op:`sphere`,center:_u(t.before),radius:e.radius,material:n});case`paint`:return JSON.stringify({op:`paint`,center:_u(t.voxel),radius:e.radius,material:n});case`flood`:return JSON.stringify({op:`flood_paint`,start:t.voxel,material:n,limit:hu})}}function wu(e){let t=e>>10&31,n=e&1023,r=e&32768?-1:1;return t===0?r*n*2**-24:t===31?n?NaN:r*(1/0):r*(1+n/1024)*2**(t-15)}function Tu(e){let t=e.words(4),n=[];for(let e=1;4*e+3<t.length;e++){let r=t[4*e+1],i=t[4*e+2],[a,o,s]=[wu(r&65535),wu(r>>>16),wu(i&65535)];n.push({id:e,colour:`rgb(${rl(a)},${rl(o)},${rl(s)})`,kind:t[4*e]&3})}return n}function Eu(e,t){let n=new Map;e.addEventListener(`pointerdown`,e=>{e.pointerType===`touch`&&n.set(e.pointerId,{x:e.clientX,y:e.clientY})}),e.addEventListener(`pointermove`,e=>{let r=n.get(e.pointerId);if(e.pointerType!==`touch`||!r)return;let[i,a]=[e.clientX-r.x,e.clientY-r.y];n.set(e.pointerId,{x:e.clientX,y:e.clientY}),n.size===1?t.look(i,a):n.size===2&&t.fly(-a/2,i/2)});for(let t of[`pointerup`,`pointercancel`])e.addEventListener(t,e=>n.delete(e.pointerId))}var Du=[`albedo`,`material`,`normal`,`steps`,`gi`,`roma`,`irradiance`,`pathtrace`],Ou=4096,ku=2*K.TAA_SLOTS,Au=8192;function ju(e){let t=new URLSearchParams(e),n={camera:void 0,mode:void 0,size:void 0,spp:void 0,problems:[]},r=t.get(`camera`);if(r!==null)try{n.camera=Ao(r)}catch(e){n.problems.push(`camera: ${e.message}; using the default view`)}let i=t.get(`mode`);i!==null&&(Du.includes(i)?n.mode=i:n.problems.push(`mode: '${i}' is not one of ${Du.join(`, `)}; using the default`));let a=t.get(`size`);if(a!==null){let e=/^(\d{1,5})x(\d{1,5})$/.exec(a),[t,r]=e?[Number(e[1]),Number(e[2])]:[0,0];t>=1&&r>=1&&t<=Au&&r<=Au?n.size=[t,r]:n.problems.push(`size: '${a}' is not WxH with edges 1..=${Au}; using the canvas size`)}let o=t.get(`spp`);if(o!==null){let e=Number(o);Number.isInteger(e)&&e>=1&&e<=Ou?n.spp=e:n.problems.push(`spp: '${o}' is not a whole number in 1..=${Ou}; using the mode's default`)}return n}function Mu(e,t,n){let r=new URLSearchParams;r.set(`camera`,jo(e)),r.set(`mode`,t),n.size&&r.set(`size`,`${n.size[0]}x${n.size[1]}`),n.spp&&r.set(`spp`,String(n.spp)),history.replaceState(null,``,`${location.pathname}?${r.toString().replace(/\+/g,`%20`)}`)}function Nu(e,t){return t.spp??(e===`gi`?ku:Ou)}var X=e=>document.getElementById(e),Z=X(`view`),Pu=X(`overlay`),Fu=X(`hud`),Iu=X(`notice`),Lu=ju(location.search),Q={state:`connecting`,version:0,growthSeq:0,quiescent:!1,digest:``,users:[],mode:Lu.mode??`albedo`,frameMs:0,message:Lu.problems.join(`
`),role:``,joins:0,snapshots:0,bytesReceived:0,snapshotBytes:0,markers:[],rateLimited:0,timings:{},shownVersion:-1,shownGeneration:-1,previewInstances:0,markerInstances:0,markerMaterials:[],presenceSession:``,samples:0,irradiance:null,pointer:null,name:``,voxel:()=>0,capture:()=>Promise.reject(Error(`no frame yet`)),redraw:()=>{},generation:()=>0,changedChunks:()=>`everything`,edit:()=>Promise.reject(Error(`not joined`)),undo:()=>Promise.reject(Error(`not joined`)),redo:()=>Promise.reject(Error(`not joined`)),hierarchy:e=>Array.from(Gc(Uint32Array.from(e))),hierarchyAfter:(e,t)=>{let n=new Kc;return n.update(Uint32Array.from(e)),Array.from(n.update(Uint32Array.from(t)))}};window.naadf=Q;function Ru(e){Iu.textContent=e,Iu.hidden=e===``}Ru(Q.message);var $=Lu.camera,zu=0;function Bu(){if(Lu.size)return Lu.size;let e=window.devicePixelRatio||1;return[Math.max(1,Math.round(Z.clientWidth*e)),Math.max(1,Math.round(Z.clientHeight*e))]}function Vu(){Fu.textContent=[`${Q.state}${Q.role?` · ${Q.role}`:``}`,`version ${Q.version}${Q.growthSeq?`.${Q.growthSeq}`:``}${Q.quiescent?``:` (settling)`}`,`digest ${Q.digest.slice(0,8)}`,`${Q.users.length} online${Q.users.length?`: ${Q.users.join(`, `)}`:``}`,`rtt ${zu.toFixed(0)} ms · frame ${Q.frameMs.toFixed(1)} ms · ${Q.mode}`].join(`
`)}function Hu(e){let[t,n]=[Z.width,Z.height];if(!e||document.pointerLockElement===Z)return[t/2,n/2];let r=Z.getBoundingClientRect(),i=Math.min(r.width/t,r.height/n),[a,o]=[(r.width-t*i)/2,(r.height-n*i)/2];return[(e.clientX-r.left-a)/i,(e.clientY-r.top-o)/i]}async function Uu(){await us();let e,t;try{({device:e,fallback:t}=await jl())}catch(e){if(e instanceof Al){Q.state=`no-webgpu`,Q.message=`${e.message}. Open this page in a browser with WebGPU (https://, or http://localhost), or use the native viewer: naadf view --server <address>`,Ru(Q.message),Vu();return}throw e}Q.timings.device=performance.now(),Lu.mode||(Q.mode=t?`albedo`:`gi`);let n=Z.getContext(`2d`),r=Pu.getContext(`2d`),i=new Ml(e),a=new Rl(e,Q.mode),o,s=[],c=[],l=[],u=!0,d=!1,f,p={tool:`voxel`,material:1,radius:4,anchor:void 0},m,h,g,_=BigInt(Math.floor(Math.random()*2**52));Q.presenceSession=_.toString();let v=e=>{i.uploadAll(e),$??=Lo(e.size),k(),b(e)},y=new uu({state(e,t){Q.state=e,Q.bytesReceived=y.bytesReceived,Q.snapshotBytes=y.snapshotBytes,e===`live`&&(Q.timings.live??=performance.now()),t!==void 0&&(Q.message=t,Ru(e===`need-token`?`${t}: enter a token`:t),e===`need-token`&&C(t)),Vu()},joined(){Q.joins+=1},snapshot(e){Q.snapshots+=1,v(e)},restored:v,patched(e,t,n){i.update(e,t,n),t.some(e=>e.id===4)&&k(),b(e)},presence(e){Q.users=e.map(e=>e.name||e.user||`anonymous`).sort(),s=e.filter(e=>e.session!==_),j(),d=!0,Vu()}},await Ys.open());function b(e){o=new Xl(e),Q.version=Number(e.version),Q.growthSeq=e.growthSeq,Q.quiescent=e.quiescent,Q.digest=fs(e.digest),Q.bytesReceived=y.bytesReceived,Q.snapshotBytes=y.snapshotBytes,u=!0,Vu()}let x=BigInt(Date.now())*1000n,S=async e=>{let t=x+=1n;for(let n=0;;n++){let r=performance.now();try{let i=await e(t);return zu=performance.now()-r,n>0&&Ru(``),Vu(),Number(i.version)}catch(e){let t=B.from(e);if(t.code===z.ResourceExhausted&&n<8){Q.rateLimited+=1,Ru(`rate-limited: ${t.rawMessage}; retrying`),await new Promise(e=>setTimeout(e,250*2**n));continue}throw Q.message=t.rawMessage,Ru(`refused: ${t.rawMessage}`),t}}};Q.edit=e=>S(t=>y.client.edit(N(wo,{ops:e,clientSeq:t}),y.callOptions())),Q.undo=()=>S(e=>y.client.undo(N(To,{clientSeq:e}),y.callOptions())),Q.redo=()=>S(e=>y.client.redo(N(To,{clientSeq:e}),y.callOptions())),Q.redraw=()=>{u=!0},Q.generation=()=>i.generation,Q.changedChunks=e=>i.changesSince(e),Q.capture=async()=>{let e=a.last;if(!e)throw Error(`no frame yet`);let t=document.createElement(`canvas`);return t.width=e.width,t.height=e.height,t.getContext(`2d`).putImageData(e,0,0),t.toDataURL(`image/png`)};function C(e){let t=X(`token`);t.hidden=!1,X(`token-why`).textContent=e,t.onsubmit=e=>{e.preventDefault(),t.hidden=!0,y.setToken(X(`token-value`).value),y.run(),w()}}async function w(){try{let e=await y.whoAmI();Q.role=e.role;let t=e.role===`viewer`;X(`tools`).classList.toggle(`disabled`,t),t&&Ru(`viewer token: editing is disabled (ask for an editor token to edit)`),Vu()}catch{}}let T=sessionStorage.getItem(`naadf.name`)??`guest-${Math.floor(Math.random()*1e4)}`;sessionStorage.setItem(`naadf.name`,T),Q.name=T,Q.voxel=(e,t,n)=>o?.inside(e,t,n)?o.cell(e,t,n).material:0;let E=``,ee=0;setInterval(()=>{if(Q.state!==`live`||!$)return;let e={session:_,name:T,position:[...$.pos],forward:Fo($).forward,pointer:m?m.voxel.map(BigInt):[],tool:p.tool},t=JSON.stringify(e,(e,t)=>typeof t==`bigint`?String(t):t),n=performance.now();t===E&&n-ee<1e3||(E=t,ee=n,y.client.publish(N(So,e),y.callOptions()).catch(()=>{}))},100);let D=X(`tool`);for(let e of mu)D.add(new Option(e,e));D.onchange=()=>{p.tool=D.value,p.anchor=void 0,d=!0};let O=X(`radius`);O.onchange=()=>{p.radius=Math.max(0,Number(O.value)||0),d=!0};function k(){let e=Tu(y.mirror);l=zl(e),X(`palette`).replaceChildren(...e.map(e=>{let t=document.createElement(`button`);return t.className=e.id===p.material?`swatch chosen`:`swatch`,t.style.background=e.colour,t.title=`material ${e.id}`,t.onclick=()=>{p.material=e.id,k()},t}))}function A(e){if(!o||Z.width===0)return;let[t,n]=Hu(g);m=Zl(o,[...e.pos],ql(e,Z.width,Z.height,t,n)),h=m&&Q.role!==`viewer`?xu(p,o,m):void 0,Q.pointer=m?{voxel:m.voxel,before:m.before}:null,c=te?Su(p,h):[],j()}function j(){let e=i.generation,t=Gl(s,y.mirror.size,l,$?.pos);i.setLocals([...c,...t]),Q.previewInstances=c.length,Q.markerInstances=t.length,Q.markerMaterials=t.map(e=>e.material),i.generation!==e&&(u=!0)}let te=!1;Z.addEventListener(`mousemove`,e=>{g=e,te=!0,d=!0}),Z.addEventListener(`mouseleave`,()=>{te=!1,d=!0}),Z.addEventListener(`contextmenu`,e=>e.preventDefault()),Z.addEventListener(`mousedown`,e=>{if(e.button===2&&document.pointerLockElement!==Z){Z.requestPointerLock?.();return}if(e.button!==0||Q.role===`viewer`||!f)return;if(g=e,A(f),!m||h?.refusal){h?.refusal&&Ru(`${p.tool}: ${h.refusal}`);return}let t=Cu(p,m);d=!0,t&&Q.edit(t).then(()=>Ru(``),()=>{})});let M=new Set,ne=32;addEventListener(`keydown`,e=>{(e.ctrlKey||e.metaKey)&&e.code===`KeyZ`?(e.preventDefault(),(e.shiftKey?Q.redo():Q.undo()).catch(()=>{})):e.target instanceof HTMLInputElement||M.add(e.code)}),addEventListener(`keyup`,e=>M.delete(e.code));let re=(e,t)=>{$&&($.yaw+=e*.15,$.pitch=Math.max(-89.9,Math.min(89.9,$.pitch-t*.15)),u=!0)};addEventListener(`mousemove`,e=>{document.pointerLockElement===Z&&re(e.movementX,e.movementY)}),Eu(Z,{look:re,fly(e,t){if(!$)return;let n=Fo($);$.pos.forEach((r,i)=>$.pos[i]+=(n.forward[i]*e+n.right[i]*t)*(ne/64)),u=!0}}),Z.addEventListener(`wheel`,e=>{ne=Math.max(1,Math.min(4096,ne*(e.deltaY<0?1.25:.8))),e.preventDefault()});let ie=[],ae=performance.now(),oe=0,se=!1;function ce(){se||(se=!0,setTimeout(()=>{se=!1,oe=performance.now(),$&&Mu($,Q.mode,Lu)},Math.max(0,500-(performance.now()-oe))))}let P=!1;function le(e){let t=Math.min(.1,(e-ae)/1e3);if(ae=e,$&&M.size>0){let e=Fo($),n=(e,n)=>e.forEach((e,r)=>$.pos[r]+=e*n*ne*t);M.has(`KeyW`)&&n(e.forward,1),M.has(`KeyS`)&&n(e.forward,-1),M.has(`KeyD`)&&n(e.right,1),M.has(`KeyA`)&&n(e.right,-1),M.has(`Space`)&&n([0,1,0],1),M.has(`ShiftLeft`)&&n([0,1,0],-1),u=!0}if(i.buffer&&$&&u&&!P){j(),u=!1,P=!0;let[e,t]=Bu(),r=performance.now(),o=Q.version,s=i.generation,c={...$,pos:[...$.pos]};a.render(i,c,e,t,Q.mode).then(e=>{for(let t of[Z,Pu])(t.width!==e.width||t.height!==e.height)&&([t.width,t.height]=[e.width,e.height]);n.putImageData(e,0,0),f=c,d=!0,ie.push(performance.now()-r),ie.length>30&&ie.shift(),Q.frameMs=ie.reduce((e,t)=>e+t,0)/ie.length,Q.shownVersion=o,Q.shownGeneration=s,Q.timings.firstFrame??=performance.now(),Q.samples=a.samples(Q.mode),Q.irradiance=a.irradianceStats,Rl.accumulates(Q.mode)&&Q.samples<Nu(Q.mode,Lu)&&(u=!0),Vu()}).catch(e=>console.error(`frame: ${e}`)).finally(()=>P=!1),ce()}d&&f&&(d=!1,A(f),Q.markers=Yl(r,f,h,s)),requestAnimationFrame(le)}requestAnimationFrame(le);let ue=X(`mode`);for(let e of Du)ue.add(new Option(e,e,!1,e===Q.mode));ue.onchange=()=>{Q.mode=ue.value,u=!0},X(`undo`).onclick=()=>Q.undo().catch(()=>{}),X(`redo`).onclick=()=>Q.redo().catch(()=>{}),X(`shot`).onclick=async()=>{let e=document.createElement(`a`);e.href=await Q.capture(),e.download=`naadf-${Q.version}.png`,e.click()},addEventListener(`resize`,()=>u=!0),w(),await y.restore()&&(Q.timings.restored=performance.now()),await y.run()}Uu().catch(e=>{Q.state=`error`,Q.message=String(e instanceof Error?e.message:e),Ru(Q.message),Vu()});