//! A run's own TLS authority, made on the fly when the user brings none: a certificate
//! authority that lives for one run, and, signed by it, the certificates of the
//! coordinator, the relays and the agents started on this host, written as the folder
//! that `--tls-dir` names ([`TlsFiles::in_dir`]).
//!
//! The authority's private key is never written: once the files are made nobody can sign
//! another certificate, so only the processes that can read the folder (the run's private
//! folder, mode 0700, of the coordinator's user) can join, and only as the role their
//! certificate names. The certificates are valid from a day before the run to 30 days
//! after it starts.

use std::io::Write;
use std::path::{Path, PathBuf};

use rcgen::{
    BasicConstraints, CertificateParams, DnType, ExtendedKeyUsagePurpose, IsCa, KeyPair,
    KeyUsagePurpose,
};

use crate::endpoint::Endpoint;
use crate::security::Role;

/// Why a run's authority could not be made.
#[derive(Debug, thiserror::Error)]
pub enum AuthorityError {
    /// A key or a certificate could not be made.
    #[error("making the run's TLS authority: {0}")]
    Certificate(#[from] rcgen::Error),
    /// A file or the folder could not be written (a file already there is refused).
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// Why it could not be written.
        source: std::io::Error,
    },
}

/// Make a run's authority in `dir` (created, mode 0700; it must not exist): `ca.pem` and,
/// for each of `roles`, `STEM.pem` and `STEM-key.pem` (mode 0600). The coordinator's
/// certificate names the loopback (`127.0.0.1`, `::1`, `localhost`) and `listen`'s host,
/// which is where sessions connect to reach it.
///
/// ```
/// use net::{Endpoint, Role, TlsFiles, make_run_authority};
/// let temp = std::env::temp_dir().join(format!("authority-doc-{}", std::process::id()));
/// let listen = Endpoint::parse("tls/127.0.0.1:7447").unwrap();
/// make_run_authority(&temp, &listen, &[Role::Coordinator, Role::Agent(0)]).unwrap();
/// let files = TlsFiles::in_dir(&temp, Role::Agent(0));
/// let pem = std::fs::read_to_string(&files.certificate).unwrap();
/// assert!(pem.starts_with("-----BEGIN CERTIFICATE-----"));
/// assert!(!temp.join("ca-key.pem").exists());
/// std::fs::remove_dir_all(&temp).unwrap();
/// ```
pub fn make_run_authority(
    dir: &Path,
    listen: &Endpoint,
    roles: &[Role],
) -> Result<(), AuthorityError> {
    use std::os::unix::fs::DirBuilderExt;
    std::fs::DirBuilder::new()
        .mode(0o700)
        .create(dir)
        .map_err(|source| AuthorityError::Io {
            path: dir.to_path_buf(),
            source,
        })?;
    let now = time::OffsetDateTime::now_utc();
    let valid = |params: &mut CertificateParams| {
        params.not_before = now - time::Duration::days(1);
        params.not_after = now + time::Duration::days(30);
    };

    let ca_key = KeyPair::generate()?;
    let mut ca = CertificateParams::new(Vec::<String>::new())?;
    ca.distinguished_name
        .push(DnType::CommonName, "formation run authority");
    ca.is_ca = IsCa::Ca(BasicConstraints::Constrained(0));
    ca.key_usages = vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign];
    valid(&mut ca);
    let ca = ca.self_signed(&ca_key)?;
    write_private(&dir.join("ca.pem"), &ca.pem())?;

    for &role in roles {
        let stem = role.stem();
        let names = match role {
            Role::Coordinator => {
                let mut names: Vec<String> =
                    vec!["127.0.0.1".into(), "::1".into(), "localhost".into()];
                let host = listen.bare_host();
                if !listen.is_unspecified() && !names.iter().any(|n| n == host) {
                    names.push(host.to_string());
                }
                names
            }
            _ => vec![format!("formation-{stem}")],
        };
        let key = KeyPair::generate()?;
        let mut leaf = CertificateParams::new(names)?;
        leaf.distinguished_name
            .push(DnType::CommonName, format!("formation {stem}"));
        leaf.is_ca = IsCa::ExplicitNoCa;
        leaf.key_usages = vec![KeyUsagePurpose::DigitalSignature];
        leaf.extended_key_usages = vec![
            ExtendedKeyUsagePurpose::ServerAuth,
            ExtendedKeyUsagePurpose::ClientAuth,
        ];
        valid(&mut leaf);
        let certificate = leaf.signed_by(&key, &ca, &ca_key)?;
        write_private(&dir.join(format!("{stem}.pem")), &certificate.pem())?;
        write_private(&dir.join(format!("{stem}-key.pem")), &key.serialize_pem())?;
    }
    Ok(())
}

/// Write `text` to a new file `path` readable by its owner only.
fn write_private(path: &Path, text: &str) -> Result<(), AuthorityError> {
    use std::os::unix::fs::OpenOptionsExt;
    let io = |source| AuthorityError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file = std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .mode(0o600)
        .open(path)
        .map_err(io)?;
    file.write_all(text.as_bytes()).map_err(io)?;
    file.sync_all().map_err(io)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::os::unix::fs::PermissionsExt;

    #[test]
    fn every_file_is_private_and_a_second_authority_in_the_same_folder_is_refused() {
        let temp = tempdir();
        let dir = temp.join("tls");
        let listen = Endpoint::parse("tls/10.0.0.1:7447").expect("endpoint");
        let roles = [Role::Coordinator, Role::Relay, Role::Agent(3)];
        make_run_authority(&dir, &listen, &roles).expect("authority");
        let mode = |p: &Path| std::fs::metadata(p).expect("metadata").permissions().mode() & 0o777;
        assert_eq!(mode(&dir), 0o700);
        let mut names: Vec<String> = std::fs::read_dir(&dir)
            .expect("read_dir")
            .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(
            names,
            [
                "agent-3-key.pem",
                "agent-3.pem",
                "ca.pem",
                "coordinator-key.pem",
                "coordinator.pem",
                "relay-key.pem",
                "relay.pem"
            ]
        );
        for name in &names {
            assert_eq!(mode(&dir.join(name)), 0o600, "{name}");
        }
        assert!(matches!(
            make_run_authority(&dir, &listen, &roles),
            Err(AuthorityError::Io { .. })
        ));
        std::fs::remove_dir_all(&temp).expect("clean up");
    }

    #[test]
    fn two_runs_have_different_authorities() {
        let temp = tempdir();
        let listen = Endpoint::parse("tls/127.0.0.1:7447").expect("endpoint");
        for run in ["a", "b"] {
            make_run_authority(&temp.join(run), &listen, &[]).expect("authority");
        }
        let ca = |run: &str| std::fs::read(temp.join(run).join("ca.pem")).expect("ca.pem");
        assert_ne!(ca("a"), ca("b"));
        std::fs::remove_dir_all(&temp).expect("clean up");
    }

    fn tempdir() -> PathBuf {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static NEXT: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "net-authority-{}-{}",
            std::process::id(),
            NEXT.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir(&dir).expect("temp dir");
        dir
    }
}
