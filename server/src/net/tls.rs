//! TLS for the gRPC listener, with a certificate that is replaced while the server runs.
//!
//! Certificates are short-lived and rotated by tools (ACME clients, cert-manager) that
//! rewrite the PEM files in place. A server that read them only at start would need a
//! restart for each rotation, dropping every client's stream. Instead [`ReloadingCert`]
//! reads the files again every [`POLL`] and on SIGHUP: a changed pair that loads is used
//! for every handshake after it, while open connections keep the one they began with. A
//! pair that does not load (a half-written file, a key that does not match the
//! certificate) is logged and counted once, a file that cannot be read at every attempt,
//! and the last good pair stays in use, so a bad rotation never takes the listener down.

use crate::metrics::Metrics;
use crate::net::conn::Conn;
use anyhow::{Context, Result, bail};
use rustls::crypto::CryptoProvider;
use rustls::pki_types::pem::PemObject;
use rustls::pki_types::{CertificateDer, PrivateKeyDer};
use rustls::server::{ClientHello, ResolvesServerCert};
use rustls::sign::CertifiedKey;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, RwLock};
use std::time::Duration;
use tokio::sync::watch;
use tokio_rustls::TlsAcceptor;
use tokio_rustls::server::TlsStream;

/// How often the certificate files are read again.
pub const POLL: Duration = Duration::from_secs(10);

/// The listener's certificate and key, read from their PEM files and read again when they
/// change (see the module docs).
#[derive(Debug)]
pub struct ReloadingCert {
    cert_path: PathBuf,
    key_path: PathBuf,
    provider: Arc<CryptoProvider>,
    /// The pair handshakes use now.
    current: RwLock<Arc<CertifiedKey>>,
    /// The files' contents when last read, loaded or not: unchanged files are not loaded
    /// again, and a bad pair is reported once, not at every poll.
    seen: Mutex<(Vec<u8>, Vec<u8>)>,
}

impl ReloadingCert {
    /// Loads the certificate chain at `cert_path` and the private key at `key_path`; fails
    /// when either cannot be read or parsed, or the key is not the certificate's.
    pub fn load(cert_path: &Path, key_path: &Path) -> Result<Self> {
        let provider = Arc::new(rustls::crypto::ring::default_provider());
        let seen = read_pair(cert_path, key_path)?;
        let current = certified_key(&seen.0, &seen.1, &provider).with_context(|| {
            format!(
                "bad TLS certificate or key ({}, {})",
                cert_path.display(),
                key_path.display()
            )
        })?;
        Ok(Self {
            cert_path: cert_path.to_owned(),
            key_path: key_path.to_owned(),
            provider,
            current: RwLock::new(Arc::new(current)),
            seen: Mutex::new(seen),
        })
    }

    /// Reads the files again and, if they changed and load, uses them from now on.
    /// `Ok(true)` when a new pair took effect, `Ok(false)` when the files are as they were
    /// when last read, an error when they cannot be read or their new contents do not load;
    /// the pair in use is unchanged then.
    pub fn reload(&self) -> Result<bool> {
        let pair = read_pair(&self.cert_path, &self.key_path)?;
        let mut seen = self.seen.lock().expect("seen lock");
        if *seen == pair {
            return Ok(false);
        }
        let loaded = certified_key(&pair.0, &pair.1, &self.provider);
        *seen = pair;
        *self.current.write().expect("certificate lock") = Arc::new(loaded?);
        Ok(true)
    }

    /// A TLS acceptor that presents whichever pair is current at each handshake and
    /// offers HTTP/2 (gRPC's transport) by ALPN.
    pub fn acceptor(self: &Arc<Self>) -> Result<TlsAcceptor> {
        let mut config = rustls::ServerConfig::builder_with_provider(self.provider.clone())
            .with_safe_default_protocol_versions()?
            .with_no_client_auth()
            .with_cert_resolver(self.clone());
        // HTTP/2 for gRPC; HTTP/1.1 too, for the browser page and gRPC-web from clients that
        // speak only that (the server tells them apart by the connection's first bytes).
        config.alpn_protocols = vec![b"h2".to_vec(), b"http/1.1".to_vec()];
        Ok(TlsAcceptor::from(Arc::new(config)))
    }

    /// Spawns the task that reloads every [`POLL`] and on SIGHUP until `shutdown` turns
    /// true, logging each outcome and counting it in `metrics`. The SIGHUP handler is in
    /// place when this returns, so a SIGHUP sent once the server is up never kills it.
    pub fn watch(self: Arc<Self>, metrics: Arc<Metrics>, shutdown: watch::Receiver<bool>) {
        let hangup = match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::hangup()) {
            Ok(s) => Some(s),
            Err(e) => {
                tracing::warn!("cannot install the SIGHUP handler ({e}); the TLS certificate reloads every {POLL:?}");
                None
            }
        };
        tokio::spawn(self.reload_loop(hangup, metrics, shutdown));
    }

    async fn reload_loop(
        self: Arc<Self>,
        mut hangup: Option<tokio::signal::unix::Signal>,
        metrics: Arc<Metrics>,
        mut shutdown: watch::Receiver<bool>,
    ) {
        let mut tick = tokio::time::interval(POLL);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        // The first tick is immediate, and the files were just loaded.
        tick.tick().await;
        loop {
            let hangup = async {
                match hangup.as_mut() {
                    Some(s) => s.recv().await,
                    None => std::future::pending().await,
                }
            };
            tokio::select! {
                _ = tick.tick() => {}
                _ = hangup => tracing::info!("SIGHUP: reading the TLS certificate and key again"),
                _ = shutdown.wait_for(|s| *s) => return,
            }
            match self.reload() {
                Ok(false) => {}
                Ok(true) => {
                    metrics.tls_reloads.inc();
                    tracing::info!(cert = %self.cert_path.display(), "TLS certificate reloaded");
                }
                Err(e) => {
                    metrics.tls_reload_failures.inc();
                    tracing::error!("TLS certificate not reloaded, the previous one stays in use: {e:#}");
                }
            }
        }
    }
}

impl ResolvesServerCert for ReloadingCert {
    fn resolve(&self, _hello: ClientHello<'_>) -> Option<Arc<CertifiedKey>> {
        Some(self.current.read().expect("certificate lock").clone())
    }
}

/// The contents of both files.
fn read_pair(cert: &Path, key: &Path) -> Result<(Vec<u8>, Vec<u8>)> {
    let read = |p: &Path| std::fs::read(p).with_context(|| format!("cannot read {}", p.display()));
    Ok((read(cert)?, read(key)?))
}

/// A certificate chain and its private key from PEM, checked to belong together.
fn certified_key(cert_pem: &[u8], key_pem: &[u8], provider: &CryptoProvider) -> Result<CertifiedKey> {
    let chain = CertificateDer::pem_slice_iter(cert_pem)
        .collect::<Result<Vec<_>, _>>()
        .context("the certificate file is not PEM")?;
    if chain.is_empty() {
        bail!("the certificate file holds no certificate");
    }
    let key = PrivateKeyDer::from_pem_slice(key_pem).context("the key file holds no private key")?;
    let signer = provider
        .key_provider
        .load_private_key(key)
        .context("unsupported private key")?;
    let certified = CertifiedKey::new(chain, signer);
    certified.keys_match().context("the key is not the certificate's")?;
    Ok(certified)
}

/// Completes the TLS handshake on `conn`, within the connection's idle timeout (a peer
/// that trickles its handshake holds its connection no longer than a silent one).
pub async fn handshake(acceptor: TlsAcceptor, conn: Conn, timeout: Duration) -> std::io::Result<TlsStream<Conn>> {
    tokio::time::timeout(timeout, acceptor.accept(conn))
        .await
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::TimedOut, "TLS handshake timed out"))?
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pair(name: &str) -> (String, String) {
        let k = rcgen::generate_simple_self_signed(vec![name.to_owned()]).unwrap();
        (k.cert.pem(), k.signing_key.serialize_pem())
    }

    fn write(dir: &Path, (cert, key): &(String, String)) -> (PathBuf, PathBuf) {
        let (c, k) = (dir.join("cert.pem"), dir.join("key.pem"));
        std::fs::write(&c, cert).unwrap();
        std::fs::write(&k, key).unwrap();
        (c, k)
    }

    fn current_der(r: &ReloadingCert) -> Vec<u8> {
        r.current.read().unwrap().cert[0].to_vec()
    }

    #[test]
    fn a_changed_pair_replaces_the_old_and_a_bad_one_is_reported_once() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (pair("a.test"), pair("b.test"));
        let (c, k) = write(dir.path(), &a);
        let r = ReloadingCert::load(&c, &k).unwrap();
        let first = current_der(&r);
        assert!(!r.reload().unwrap(), "unchanged files");

        // A rotation caught halfway: B's certificate with A's key.
        std::fs::write(&c, &b.0).unwrap();
        let err = r.reload().unwrap_err();
        assert!(format!("{err:#}").contains("not the certificate's"), "{err:#}");
        assert_eq!(current_der(&r), first, "the last good pair stays");
        assert!(!r.reload().unwrap(), "a bad pair is reported once");

        std::fs::write(&k, &b.1).unwrap();
        assert!(r.reload().unwrap());
        let second = current_der(&r);
        assert_ne!(second, first);
        let expected = CertificateDer::from_pem_slice(b.0.as_bytes()).unwrap();
        assert_eq!(second, expected.to_vec());

        // Garbage, then a missing file: errors, and B stays in use.
        std::fs::write(&c, "not a certificate").unwrap();
        assert!(r.reload().is_err());
        std::fs::remove_file(&k).unwrap();
        assert!(format!("{:#}", r.reload().unwrap_err()).contains("cannot read"));
        assert_eq!(current_der(&r), second);
    }

    #[test]
    fn a_bad_pair_fails_at_start() {
        let dir = tempfile::tempdir().unwrap();
        let (a, b) = (pair("a.test"), pair("b.test"));
        let (c, k) = write(dir.path(), &(a.0, b.1));
        let err = ReloadingCert::load(&c, &k).unwrap_err();
        assert!(format!("{err:#}").contains("not the certificate's"), "{err:#}");
        std::fs::write(&c, "").unwrap();
        let err = ReloadingCert::load(&c, &k).unwrap_err();
        assert!(format!("{err:#}").contains("no certificate"), "{err:#}");
    }
}
