// Runs the Khronos glTF Validator on one .gltf or .glb and prints its report as JSON:
//   node gltf_validate.js VALIDATOR_DIR FILE
// VALIDATOR_DIR holds node_modules/gltf-validator (scripts/deps installs it). External buffers and
// images are read from FILE's folder.
'use strict';
const fs = require('fs');
const path = require('path');

const validator = require(path.join(process.argv[2], 'node_modules', 'gltf-validator'));
const file = process.argv[3];
const folder = path.dirname(file);

validator
  .validateBytes(new Uint8Array(fs.readFileSync(file)), {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      new Promise((resolve, reject) => {
        fs.readFile(path.join(folder, decodeURIComponent(uri)), (err, data) => {
          if (err) reject(err.toString());
          else resolve(new Uint8Array(data));
        });
      }),
  })
  .then(
    (report) => console.log(JSON.stringify(report)),
    (error) => {
      console.error(String(error));
      process.exit(1);
    });
