#!/usr/bin/env bash
# Makes a test PKI for Lockstep's DDS Security profile (openssl only):
#   OUT/ca.cert.pem, ca.key.pem      a self-signed CA (identity CA and permissions CA)
#   OUT/<name>.cert.pem, .key.pem    one certificate per identity (subject CN=<name>), EC P-256
#   OUT/governance.p7s               deploy/security/governance.xml signed by the CA (S/MIME)
#   OUT/permissions.xml, .p7s        a grant per identity: domains 0-232, publish and
#                                    subscribe lockstep/* (the governance encrypts them)
#
#   deploy/security/make_pki.sh [--out DIR] [--days N] [NAME ...]
#
# OUT defaults to deploy/security/pki (beside deploy/security/fastdds.xml, which names
# ${QOS_DIR}/pki/...). Default names: coordinator, the services of deploy/configs and
# deploy/compose (air_sim ground_sim sensors render recorder), noop, and "client": every
# process whose name has no certificate (lockstep status/hashes/up, Python clients)
# authenticates as "client". A test CA: for production, use your own CA and keep keys
# out of images and repositories.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
out="$here/pki"
days=3650
names=()
while [ $# -gt 0 ]; do
  case "$1" in
    --out) out=$2; shift 2 ;;
    --days) days=$2; shift 2 ;;
    -h|--help) sed -n '2,18p' "$0"; exit 0 ;;
    -*) echo "make_pki.sh: unknown option $1" >&2; exit 2 ;;
    *) names+=("$1"); shift ;;
  esac
done
[ ${#names[@]} -gt 0 ] || names=(coordinator air_sim ground_sim sensors render recorder noop client ros2_bridge)
for n in "${names[@]}"; do
  [[ "$n" =~ ^[A-Za-z0-9_.-]+$ ]] || { echo "make_pki.sh: '$n' is not a valid identity name (letters, digits, _ . -)" >&2; exit 2; }
done
command -v openssl >/dev/null || { echo "make_pki.sh: openssl missing (apt-get install openssl)" >&2; exit 1; }
mkdir -p "$out"
cd "$out"
umask 077
ec() { openssl ecparam -name prime256v1 -genkey -noout -out "$1" 2>/dev/null; }

if [ ! -f ca.cert.pem ] || [ ! -f ca.key.pem ]; then
  ec ca.key.pem
  openssl req -x509 -new -key ca.key.pem -sha256 -days "$days" -subj "/CN=Lockstep test CA" \
    -addext "basicConstraints=critical,CA:TRUE" -addext "keyUsage=critical,keyCertSign,cRLSign,digitalSignature" -out ca.cert.pem
fi
not_before=$(date -u +%Y-%m-%dT%H:%M:%S -d '-1 day')
not_after=$(date -u +%Y-%m-%dT%H:%M:%S -d "+$days days")
{
  echo '<?xml version="1.0" encoding="UTF-8"?>'
  echo '<!-- Made by deploy/security/make_pki.sh: one grant per identity. -->'
  echo '<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance"'
  echo '     xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">'
  echo '  <permissions>'
} > permissions.xml
for n in "${names[@]}"; do
  if [ ! -f "$n.cert.pem" ]; then
    ec "$n.key.pem"
    openssl req -new -key "$n.key.pem" -subj "/CN=$n" -out "$n.csr" 2>/dev/null
    openssl x509 -req -in "$n.csr" -CA ca.cert.pem -CAkey ca.key.pem -CAcreateserial -sha256 -days "$days" \
      -out "$n.cert.pem" 2>/dev/null
    rm -f "$n.csr"
  fi
  # The ROS 2 bridge alone may also use ROS 2's topics (rt/..., CARLA's ROS 2 names).
  topics='<topic>lockstep/*</topic>'
  [ "$n" != ros2_bridge ] || topics="$topics<topic>rt/*</topic>"
  subject=$(openssl x509 -in "$n.cert.pem" -noout -subject -nameopt RFC2253 | sed 's/^subject=//')
  cat >> permissions.xml <<XML
    <grant name="lockstep.$n">
      <subject_name>$subject</subject_name>
      <validity><not_before>$not_before</not_before><not_after>$not_after</not_after></validity>
      <allow_rule>
        <domains><id_range><min>0</min><max>232</max></id_range></domains>
        <publish><topics>$topics</topics></publish>
        <subscribe><topics>$topics</topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
XML
done
echo '  </permissions>' >> permissions.xml
echo '</dds>' >> permissions.xml
openssl smime -sign -in "$here/governance.xml" -text -out governance.p7s -signer ca.cert.pem -inkey ca.key.pem
openssl smime -sign -in permissions.xml -text -out permissions.p7s -signer ca.cert.pem -inkey ca.key.pem
chmod 644 ./*.pem ./*.p7s permissions.xml
chmod 600 ./*.key.pem
echo "make_pki.sh: $out: CA and ${#names[@]} identities (${names[*]})"
